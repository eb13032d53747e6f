"""The app's options given before a sub-command: the command takes them, or says where
they go; `serve` opens its tabs with all of them."""

from __future__ import annotations

import argparse
import json
import shlex
from pathlib import Path

import pytest

from tui_gym.cli import build_parser, main
from tui_gym.cli.main import _app_parser, _pass_app_options
from tui_gym.cli.output import CliError

LAKE = "SFFH\nFFFH\nHFFG\n"  # not one of the built-in maps


def _commands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_a_map_file_before_the_command_is_the_commands_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lake = tmp_path / "lake.txt"
    lake.write_text(LAKE)
    code, before, _ = _run(capsys, "--map-file", str(lake), "optimal", "frozenlake", "--json")
    assert code == 0
    code, after, _ = _run(capsys, "optimal", "frozenlake", "--map-file", str(lake), "--json")
    assert code == 0 and json.loads(before) == json.loads(after)
    code, default, _ = _run(capsys, "optimal", "frozenlake", "--json")
    assert json.loads(default) != json.loads(before)


def test_an_app_option_no_command_takes_is_one_line_naming_it(
    capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = _run(capsys, "--load", "agent.tgym", "eval", "agent.tgym")
    assert code == 2 and out == ""
    assert err == ("tui-gym: error: --load before `eval` is an option of the app (and of "
                   "serve), not of eval: see `tui-gym eval --help`\n")
    code, _, err = _run(capsys, "--env", "gridworld", "optimal", "blackjack")
    assert code == 2 and err.count("\n") == 1 and "takes its game after its name" in err


SAMPLES = {"--env": "gridworld", "--seed": "5", "--load": "a.tgym", "--map-file": "m.txt",
           "--record": "r.jsonl", "--runner": "thread", "--db": "runs.db", "--no-history": None}


@pytest.mark.parametrize("command", sorted(_commands(build_parser())))
def test_no_app_option_is_dropped_silently(command: str) -> None:
    parser = build_parser()
    app_flags = [a.option_strings[0] for a in _app_parser()._actions
                 if a.option_strings and a.dest not in ("help", "version")]
    assert sorted(app_flags) == sorted(SAMPLES)
    for flag, value in SAMPLES.items():
        argv = [flag] if value is None else [flag, value]
        args = argparse.Namespace(command=command)
        try:
            _pass_app_options(parser, [*argv, command], args)
        except CliError as exc:
            assert str(exc).startswith(f"{flag} before `{command}`")
            continue
        if command in ("serve", "replay"):
            continue  # the apps they open read the app's options themselves
        assert len(vars(args)) == 2, (flag, command)  # the command's own flag took it


def test_the_seed_before_train_seeds_the_run(capsys: pytest.CaptureFixture[str]) -> None:
    short = ["--episodes", "5", "--eval-episodes", "5", "--no-record", "--json"]
    runs = []
    for argv in (["--seed", "4", "train", "blackjack"], ["train", "blackjack", "--seed", "4"],
                 ["train", "blackjack"]):
        code, out, _ = _run(capsys, *argv, *short)
        assert code == 0
        runs.append({k: v for k, v in json.loads(out).items() if "second" not in k})
    assert runs[0] == runs[1] != runs[2]


def test_serve_opens_each_tab_with_the_apps_options(tmp_path: Path) -> None:
    from tui_gym.web import app_command

    argv = ["--env", "frozenlake", "--map-file", "lake.txt", "--db", "runs.db",
            "--no-history", "--runner", "thread", "--load", "a.tgym", "serve"]
    words = shlex.split(app_command(build_parser().parse_args(argv)))
    assert words[words.index("-m") + 2:] == [
        "--env", "frozenlake", "--runner", "thread", "--load", "a.tgym",
        "--map-file", "lake.txt", "--db", "runs.db", "--no-history",
    ]


def test_serve_says_a_map_file_it_cannot_read_before_serving(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "none.txt"
    code, _, err = _run(capsys, "--env", "frozenlake", "--map-file", str(missing), "serve")
    assert code == 2 and err == f"tui-gym: error: --map-file {missing}: no such file\n"
