"""The `tui-gym` command: listings, train/eval/optimal as JSON, and one-line errors."""

from __future__ import annotations

import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tui_gym import __version__
from tui_gym.cli import attach_negative_values, build_parser, main
from tui_gym.cli.commands import _eval_rows
from tui_gym.cli.main import app_arguments
from tui_gym.core.wrappers import CATALOG

REPO = Path(__file__).resolve().parents[1]
EVAL_KEYS = {"env_id", "episodes", "mean_return", "std_return"}
BLACKJACK_EVAL_KEYS = EVAL_KEYS | {
    "win_rate",
    "draw_rate",
    "loss_rate",
    "exact_value",
    "optimal_value",
    "gap",
}
GRIDWORLD_EVAL_KEYS = EVAL_KEYS | {
    "success_rate", "optimal_pair_fraction", "exact_value", "optimal_value", "gap"
}


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """The CLI in-process: exit code, stdout, stderr."""
    try:
        code = main(list(args))
    except SystemExit as exit_:  # argparse errors and --version exit this way
        code = exit_.code if isinstance(exit_.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    code, out, err = run(capsys, *args)
    assert code == 0, err
    assert err == ""
    lines = out.strip().splitlines()
    assert len(lines) == 1, "--json prints exactly one JSON object"
    return json.loads(lines[0])


def console_script() -> list[str]:
    """The installed `tui-gym` script beside this interpreter (`python -m tui_gym` without one)."""
    script = Path(sys.executable).with_name("tui-gym")
    return [str(script)] if script.exists() else [sys.executable, "-m", "tui_gym"]


def run_script(*args: str, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    """The real `tui-gym` command, as a person runs it."""
    env = {**os.environ, "COLUMNS": "120"}
    return subprocess.run(
        [*console_script(), *args], capture_output=True, text=True, timeout=120, env=env,
        cwd=REPO, **kwargs,
    )


def run_module(*args: str) -> subprocess.CompletedProcess[str]:
    """`python -m tui_gym ...` in a fresh interpreter."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "COLUMNS": "120"}
    return subprocess.run(
        [sys.executable, "-m", "tui_gym", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
        cwd=REPO,
    )


# -- listings -------------------------------------------------------------------


def test_envs_lists_the_games(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "envs")
    assert code == 0 and err == ""
    for text in ("blackjack", "Blackjack-v1", "gridworld", "tui_gym/GridWorld-v0",
                 "gymnasium_env/GridWorld-v0", "stick, hit"):
        assert text in out


@pytest.mark.parametrize("columns", ["60", "80", "120"])
def test_wrappers_lists_the_catalog_and_the_syntax(
    columns: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", columns)
    code, out, err = run(capsys, "wrappers")
    assert code == 0 and err == ""
    assert "NAME:key=value,key=value" in out
    words = set(re.findall(r"[\w.]+", out))
    for name, spec in CATALOG.items():
        assert name in words
        for param in spec.params:  # whole, as they must be typed
            assert param.name in words
    assert "=100 in [1, 100000]" in out  # parameters with their defaults and ranges
    assert "…" not in out


def test_algorithms_show_defaults_as_they_are_typed(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "160")
    code, out, err = run(capsys, "algorithms")
    assert code == 0 and err == ""
    assert "=true (true or false)" in out and "=10 in [0, 1000]" in out
    assert "True" not in out


def test_envs_json(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "envs", "--json")
    games = {game["name"]: game for game in data["envs"]}
    assert set(games) == {"blackjack", "gridworld", "frozenlake", "cliffwalking", "taxi",
                          "ab-grid", "corner-grid", "gambler", "car-rental", "random-walk",
                          "windy", "windy-king", "dyna-maze", "blocking-maze",
                          "shortcut-maze", "max-bias"}
    assert games["blackjack"]["env_id"] == "Blackjack-v1"
    assert games["blackjack"]["actions"] == ["stick", "hit"]
    assert "gymnasium_env/GridWorld-v0" in games["gridworld"]["other_ids"]
    size = {p["name"]: p for p in games["gridworld"]["params"]}["size"]
    assert size["type"] == "int" and size["default"] == 5 and size["range"] == "[2, 12]"


def test_wrappers_json(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "wrappers", "--json")
    entries = {w["name"]: w for w in data["wrappers"]}
    assert list(entries) == list(CATALOG)
    limit = entries["TimeLimit"]["params"][0]
    assert limit["name"] == "max_episode_steps" and limit["default"] == 100
    assert (limit["minimum"], limit["maximum"]) == (1, 100000)
    assert entries["FlattenObservation"]["params"] == []
    assert entries["FlattenObservation"]["changes_observation"] is True
    assert "--wrapper NAME:key=value" in data["syntax"]


def test_screenshots_json(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
                          tmp_path: Path) -> None:
    import tui_gym.ui.screenshots as screenshots

    written = [tmp_path / "a.svg", tmp_path / "b.svg"]
    monkeypatch.setattr(screenshots, "write_screenshots", lambda directory: written)
    assert run_json(capsys, "screenshots", str(tmp_path), "--json") == {
        "schema": 1, "written": [str(p) for p in written]
    }


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "--version")
    assert code == 0 and out.strip() == f"tui-gym {__version__}"


# -- train, eval, optimal -------------------------------------------------------


def test_train_gridworld_json_then_eval(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "grid.tgym"
    data = run_json(
        capsys, "train", "gridworld", "--episodes", "2000", "--eval-episodes", "1000",
        "--json", "--save", str(path),
    )
    assert {"env_id", "episodes", "seconds", "episodes_per_second", "eval"} <= set(data)
    assert data["env_id"] == "tui_gym/GridWorld-v0"
    assert data["episodes"] == 2000 and data["hyperparameters"]["episodes"] == 2000
    assert data["seconds"] > 0 and data["episodes_per_second"] > 0
    assert data["saved"] == str(path)
    assert set(data["eval"]) >= GRIDWORLD_EVAL_KEYS
    assert data["eval"]["episodes"] == 1000

    evaluated = run_json(capsys, "eval", str(path), "--episodes", "500", "--json")
    assert set(evaluated) == {"schema", *data["eval"]}
    assert set(evaluated) >= GRIDWORLD_EVAL_KEYS
    assert 0.0 <= evaluated["success_rate"] <= 1.0
    # The exact figure depends only on the table, which the file kept.
    assert evaluated["optimal_pair_fraction"] == data["eval"]["optimal_pair_fraction"]


def test_train_blackjack_save_then_eval(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "bj.tgym"
    data = run_json(
        capsys, "train", "blackjack", "--episodes", "2000", "--eval-episodes", "2000",
        "--json", "--save", str(path),
    )
    assert data["env_id"] == "Blackjack-v1" and data["episodes"] == 2000
    assert path.is_file()
    assert set(data["eval"]) >= BLACKJACK_EVAL_KEYS

    evaluated = run_json(capsys, "eval", str(path), "--json")
    assert set(evaluated) >= BLACKJACK_EVAL_KEYS
    assert set(evaluated) == {"schema", *data["eval"]}
    assert evaluated["env_id"] == "Blackjack-v1"
    assert evaluated["episodes"] == 10_000  # the default
    rates = evaluated["win_rate"] + evaluated["draw_rate"] + evaluated["loss_rate"]
    assert rates == pytest.approx(1.0)
    assert evaluated["gap"] == pytest.approx(evaluated["optimal_value"] - evaluated["exact_value"])
    assert evaluated["optimal_value"] == pytest.approx(-0.0466, abs=5e-5)
    assert evaluated["exact_value"] == data["eval"]["exact_value"]
    # Sampled against exact: 10k hands of sd <= 1 put the mean within 0.05 (5 sd).
    assert abs(evaluated["mean_return"] - evaluated["exact_value"]) < 5 / 100


def test_eval_is_reproducible_with_a_seed(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "bj.tgym"
    run_json(capsys, "train", "blackjack", "--episodes", "300", "--eval-episodes", "100",
             "--json", "--save", str(path))
    first = run_json(capsys, "eval", str(path), "--episodes", "400", "--seed", "5", "--json")
    again = run_json(capsys, "eval", str(path), "--episodes", "400", "--seed", "5", "--json")
    assert first == again


def test_train_and_eval_print_tables_without_json(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "bj.tgym"
    code, out, err = run(capsys, "train", "blackjack", "--episodes", "300", "--eval-episodes",
                         "100", "--wrapper", "StepPenalty:penalty=0.1", "--save", str(path))
    assert code == 0 and err == ""
    assert "Training summary" in out and "StepPenalty" in out and "exact value" in out
    code, out, err = run(capsys, "eval", str(path), "--episodes", "100")
    assert code == 0 and err == "" and "Evaluation" in out and "win rate" in out


def test_train_json_lists_wrappers_with_their_parameters(
    capsys: pytest.CaptureFixture[str],
) -> None:
    data = run_json(
        capsys, "train", "gridworld", "--size", "3", "--episodes", "50", "--eval-episodes", "10",
        "--wrapper", "TimeLimit:max_episode_steps=40", "--wrapper", "StepPenalty", "--json",
    )
    assert data["wrappers"] == [
        {"name": "TimeLimit", "params": {"max_episode_steps": 40},
         "spec": "TimeLimit:max_episode_steps=40"},
        {"name": "StepPenalty", "params": {"penalty": 0.01}, "spec": "StepPenalty:penalty=0.01"},
    ]


def test_a_negative_value_after_its_flag_is_a_value(capsys: pytest.CaptureFixture[str]) -> None:
    assert attach_negative_values(["train", "x", "--discount", "-0.5", "-h"]) == [
        "train", "x", "--discount=-0.5", "-h",
    ]
    assert attach_negative_values(["--lr", "-inf", "--", "--a", "-1"]) == [
        "--lr=-inf", "--", "--a", "-1",
    ]
    data = run_json(capsys, "train", "gridworld", "--size", "2", "--episodes", "20",
                    "--eval-episodes", "5", "--wrapper", "ScaleReward:factor=-2", "--json")
    assert data["wrappers"][0]["params"] == {"factor": -2.0}


@pytest.mark.parametrize("argv", [
    [], ["--env", "gridworld", "--seed=7"], ["--seed", "3", "--runner", "thread", "--no-h"],
    ["--db", "runs.db", "--load", "a.tgym", "--map-file", "m.txt"],
])
def test_the_apps_arguments_read_as_the_full_parser_reads_them(argv: list[str]) -> None:
    assert app_arguments(argv) == build_parser().parse_args(argv)


@pytest.mark.parametrize("argv", [
    ["envs"], ["-h"], ["--help"], ["--seed", "3", "train", "gridworld"], ["--bogus"], ["x"],
])
def test_anything_but_the_apps_options_goes_to_the_full_parser(argv: list[str]) -> None:
    assert app_arguments(argv) is None


def test_hyperparameter_flags_reach_the_run(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "train", "blackjack", "--episodes", "50", "--eval-episodes", "10",
                    "--learning-rate", "0.2", "--discount", "0.9", "--epsilon-final", "0.3",
                    "--json")
    hp = data["hyperparameters"]
    assert (hp["learning_rate"], hp["discount"], hp["epsilon_final"]) == (0.2, 0.9, 0.3)


def test_optimal_blackjack_json(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "optimal", "blackjack", "--json")
    assert data["optimal_value"] == pytest.approx(-0.0466, abs=5e-5)
    policy = data["policy"]
    assert len(policy) == 280  # every decision state: hard 4-21, soft 12-21, dealer A-10
    assert all(set(e) == {"state", "actions", "value"} for e in policy)
    assert {a for e in policy for a in e["actions"]} == {"stick", "hit"}
    cells = {tuple(e["state"]) for e in policy}
    assert cells >= {(s, d, u) for s in range(12, 22) for d in range(1, 11) for u in (0, 1)}
    chart = {tuple(e["state"]): e["actions"] for e in policy}
    # Basic strategy landmarks: stand on hard 17+, hit hard 12 against a 2, stand on 13 v 6.
    assert all(chart[(s, d, 0)] == ["stick"] for s in range(17, 22) for d in range(1, 11))
    assert chart[(12, 2, 0)] == ["hit"] and chart[(13, 6, 0)] == ["stick"]

    sab = run_json(capsys, "optimal", "blackjack", "--sab", "--json")
    assert sab["optimal_value"] != pytest.approx(data["optimal_value"], abs=1e-4)
    assert sab["env_kwargs"]["sab"] is True and data["env_kwargs"]["sab"] is False


def test_optimal_tables_say_what_their_marks_mean(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "optimal", "blackjack")
    assert code == 0 and "\u22120.04656" in out and "usable ace" in out
    legend = " ".join(out.split())
    assert "· tie * not optimal" in legend  # the legend names the mark it explains
    code, out, _ = run(capsys, "optimal", "gridworld", "--size", "3")
    assert code == 0 and "* off every shortest path" in " ".join(out.split())
    assert "→" in out  # the optimal moves, drawn


def test_optimal_gridworld_lists_its_policy_with_returns_and_steps(
    capsys: pytest.CaptureFixture[str],
) -> None:
    data = run_json(capsys, "optimal", "gridworld", "--size", "2", "--step-penalty", "0.25",
                    "--json")
    # 2x2: of the 12 ordered pairs of distinct cells, 8 are 1 step apart and 4 are 2.
    assert data["optimal_mean_steps"] == pytest.approx(16 / 12)
    # optimal_value is a return, as in an evaluation: +1 on the target, -0.25 a step before.
    assert data["optimal_value"] == pytest.approx(1 - 0.25 * 4 / 12)
    rows = {(tuple(r["state"]["agent"]), tuple(r["state"]["target"])): r for r in data["policy"]}
    assert len(rows) == 16 and all(set(r) == {"state", "actions", "value"} for r in rows.values())
    assert rows[(0, 0), (1, 1)] == {"state": {"agent": [0, 0], "target": [1, 1]},
                                    "actions": ["right", "up"], "value": 0.75}
    assert rows[(0, 0), (0, 1)]["actions"] == ["up"] and rows[(0, 0), (0, 1)]["value"] == 1.0
    trained = run_json(capsys, "train", "gridworld", "--size", "2", "--step-penalty", "0.25",
                       "--episodes", "300", "--eval-episodes", "10", "--no-record", "--json")
    assert trained["eval"]["optimal_value"] == pytest.approx(data["optimal_value"])
    code, out, _ = run(capsys, "optimal", "gridworld", "--size", "2", "--step-penalty", "0.25")
    assert code == 0
    assert "Exact value of the optimum: +0.91667" in out and "Optimal mean steps: 1.3333" in out


# -- errors ---------------------------------------------------------------------


def _corrupt(tmp_path: Path) -> Path:
    path = tmp_path / "corrupt.tgym"
    path.write_bytes(b"PK\x03\x04 not really a zip")
    return path


ERRORS = {
    "unknown env": (["train", "nosuchgame"], "'nosuchgame'"),
    "unknown wrapper": (["train", "blackjack", "--wrapper", "Nope"], "'Nope'"),
    "bad wrapper param": (
        ["train", "gridworld", "--wrapper", "TimeLimit:max_episode_steps=abc"],
        "TimeLimit.max_episode_steps must be an integer",
    ),
    "malformed wrapper spec": (["train", "gridworld", "--wrapper", "TimeLimit:50"], "key=value"),
    "misfit wrapper": (["train", "blackjack", "--wrapper", "DistanceShaping"], "does not fit"),
    "learning rate out of range": (
        ["train", "blackjack", "--learning-rate", "2"],
        "--learning-rate is out of range: '2' is not in (0, 1]",
    ),
    "learning rate -inf": (
        ["train", "blackjack", "--learning-rate", "-inf"],
        "--learning-rate is out of range: '-inf' is not in (0, 1]",
    ),
    "discount -1e5": (
        ["train", "blackjack", "--discount", "-1e5"],
        "--discount is out of range: '-1e5' is not in [0, 1]",
    ),
    "learning rate 1e400": (
        ["train", "blackjack", "--learning-rate", "1e400"],
        "--learning-rate is out of range: '1e400'",
    ),
    "learning rate nan": (
        ["train", "blackjack", "--learning-rate", "nan"],
        "--learning-rate must be a number in (0, 1], got 'nan'",
    ),
    "episodes too many": (
        ["train", "blackjack", "--episodes", "1e10"],
        "--episodes is out of range: '1e10' is not in [1, 1000000000]",
    ),
    "wrapper param out of range": (
        ["train", "gridworld", "--wrapper", "TimeLimit:max_episode_steps=0"],
        "TimeLimit.max_episode_steps is out of range: '0' is not in [1, 100000]",
    ),
    "wrapper param of 309 digits": (
        ["train", "blackjack", "--wrapper", "ScaleReward:factor=1" + "0" * 309],
        "ScaleReward.factor is out of range: '100000000000…000000' (310 characters)",
    ),
    "wrapper param of 5000 digits": (
        ["train", "blackjack", "--wrapper", "ScaleReward:factor=-" + "9" * 5000],
        "ScaleReward.factor is out of range",
    ),
    "arabic-indic episodes": (["train", "blackjack", "--episodes", "\u0663"], "'\u0663'"),
    "arabic-indic eval episodes": (["train", "blackjack", "--eval-episodes", "\u0663"], "'\u0663'"),
    "arabic-indic seed": (["--seed", "\u0663", "envs"], "--seed"),
    "arabic-indic size": (["optimal", "gridworld", "--size", "\u0663"], "--size must be an"),
    "superscript wrapper param": (
        ["train", "gridworld", "--wrapper", "TimeLimit:max_episode_steps=\u00b2"],
        "must be an integer in [1, 100000], got '\u00b2'",
    ),
    "target gap -inf": (["train", "blackjack", "--target-gap", "-inf"], "out of range"),
    "seed too large": (["train", "blackjack", "--seed", "9" * 40], "out of range"),
    "empty save path": (["train", "blackjack", "--save", ""], "--save: the path is empty"),
    "learning rate not a number": (["train", "blackjack", "--learning-rate", "fast"], "'fast'"),
    "epsilon final above start": (
        ["train", "blackjack", "--epsilon-start", "0.1", "--epsilon-final", "0.5"],
        "--epsilon-final",
    ),
    "zero episodes": (["train", "blackjack", "--episodes", "0"], "--episodes"),
    "seed not a number": (["--seed", "abc", "envs"], "--seed"),
    "train seed not a number": (["train", "blackjack", "--seed", "x1"], "--seed"),
    "size for blackjack": (["train", "blackjack", "--size", "4"], "--size"),
    "sab for gridworld": (["optimal", "gridworld", "--sab"], "--sab"),
    "gridworld too big": (
        ["train", "gridworld", "--size", "50"], "--size is out of range: '50' is not in [2, 12]"
    ),
    "unknown sub-command": (["frobnicate"], "'frobnicate'"),
    "arabic-indic map seed": (["maps", "--random", "4x4", "--map-seed", "\u0661\u0662"],
                              "--map-seed: expected an integer in [0,"),
    "arabic-indic density": (["maps", "--random", "4x4", "--density", "\u0660.\u0663"],
                             "--density: expected a number in [0, 0.8], got"),
    "negative map seed": (["maps", "--random", "4x4", "--map-seed", "-5"],
                          "--map-seed: '-5' is out of range"),
    "density too high": (["maps", "--random", "4x4", "--density", "0.9"],
                         "--density: '0.9' is out of range"),
    "map seed of 5000 digits": (["maps", "--random", "4x4", "--map-seed", "9" * 5000],
                                "(5,000 characters) is out of range"),
}
# Input of 5,000 characters, wherever a message echoes it: cut to its ends and its length.
LONG = "x" * 4994 + "\x1b]2;t\x07"
ECHOES = {
    "sub-command": [LONG],
    "extra argument": ["envs", LONG],
    "env": ["train", LONG],
    "choice": ["maps", "--random", "4x4", "--obstacle", LONG],
    "map name": ["maps", LONG],
    "random map size": ["maps", "--random", LONG],
    "game flag": ["optimal", "gridworld", "--size", LONG],
    "compare setting": ["compare", "blackjack", "--algorithms", "sarsa", "--no-record",
                        "--set", LONG],
    "benchmark parameter": ["benchmark", "blackjack", "--agent", "random", "--param", LONG],
}


@pytest.mark.parametrize("case", list(ERRORS))
def test_errors_exit_2_with_one_line(case: str, capsys: pytest.CaptureFixture[str]) -> None:
    args, fragment = ERRORS[case]
    code, out, err = run(capsys, *args)
    assert code == 2
    assert out == ""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), err
    assert lines[0].startswith("tui-gym")
    assert fragment in lines[0]
    for internal in ("invalid literal", "could not convert", "Exceeds the limit", "Error:"):
        assert internal not in lines[0]
    assert len(lines[0]) < 300


@pytest.mark.parametrize("case", list(ECHOES))
def test_errors_cut_the_input_they_echo(case: str, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, *ECHOES[case])
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and len(lines[0]) < 300, lines
    # The length of the input as quoted (its escapes written out) or as given.
    assert re.search(r"… ?\S* \(5,00[06] characters\)", lines[0]) and "\x1b" not in lines[0]


@pytest.mark.parametrize("kind", ["missing", "corrupt", "folder", "json"])
def test_unreadable_files_exit_2_naming_the_file(
    kind: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    if kind == "missing":
        path = tmp_path / "missing.tgym"
    elif kind == "corrupt":
        path = _corrupt(tmp_path)
    elif kind == "folder":
        path = tmp_path
    else:
        path = tmp_path / "data.json"
        path.write_text('{"q": []}')
    code, out, err = run(capsys, "eval", str(path), "--json")
    assert code == 2 and out == ""
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and str(path) in lines[0]


# -- saving and evaluating -------------------------------------------------------


def test_the_save_folder_is_checked_before_training(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # A billion episodes would take hours: the refusal must come before any of them.
    path = tmp_path / "missing" / "bj.tgym"
    code, out, err = run(capsys, "train", "blackjack", "--episodes", "1000000000",
                         "--save", str(path))
    assert (code, out) == (2, "")
    assert err == (f"tui-gym train: error: argument --save: {path}: the folder {path.parent} "
                   "does not exist\n")


def test_save_through_a_symlink_writes_its_target(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    target = tmp_path / "agents" / "bj.tgym"
    target.parent.mkdir()
    link = tmp_path / "latest.tgym"
    link.symlink_to(target)
    for _ in range(2):
        data = run_json(capsys, "train", "blackjack", "--episodes", "100", "--eval-episodes",
                        "10", "--save", str(link), "--json")
        assert data["saved"] == str(link)
        assert link.is_symlink() and target.is_file()
    assert run_json(capsys, "eval", str(link), "--episodes", "10", "--json")["episodes"] == 10


def test_the_evaluation_is_exact_and_its_sample_stops_at_the_step_budget(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from tui_gym.session.evaluation import EVAL_STEP_BUDGET

    # An agent trained for 50 episodes on an 8x8 grid often loops until the 300-step limit.
    data = run_json(capsys, "train", "gridworld", "--size", "8", "--episodes", "50", "--seed",
                    "0", "--json")
    report = data["eval"]
    assert 0.0 <= report["exact_value"] < report["optimal_value"] == pytest.approx(1.0)
    assert report["gap"] == pytest.approx(report["optimal_value"] - report["exact_value"])
    assert "exact_reason" not in report and "reference_note" not in report
    assert report["episodes_requested"] == 10_000
    assert report["step_budget"] == EVAL_STEP_BUDGET
    assert EVAL_STEP_BUDGET / 300 <= report["episodes"] < 10_000
    rows = dict(_eval_rows(report))  # what the summary table shows without --json
    assert rows["exact value (greedy policy)"] == f"{report['exact_value']:+.4f}"
    assert rows["gap to the optimum"] == f"{report['gap']:.4f}"
    assert rows["sampled episodes"] == (
        f"{report['episodes']} of 10,000 (stopped at the {EVAL_STEP_BUDGET:,}-step budget)"
    )
    assert rows["sampled mean return"] == f"{report['mean_return']:+.4f}"
    small = run_json(capsys, "train", "gridworld", "--size", "2", "--episodes", "500",
                     "--eval-episodes", "300", "--json")
    assert small["eval"]["episodes"] == small["eval"]["episodes_requested"] == 300
    assert "step_budget" not in small["eval"]
    assert small["eval"]["gap"] == 0.0  # a 2x2 grid is learnt in 500 episodes


def test_eval_rows_say_why_there_is_no_exact_value() -> None:
    rows = dict(_eval_rows({"env_id": "x", "episodes": 5, "mean_return": 1.0,
                            "std_return": 0.0, "exact_reason": "StickyAction changes it"}))
    assert rows["exact value"] == "n/a (StickyAction changes it)"
    assert rows["sampled episodes"] == "5"


def test_bad_save_files_are_one_line_and_exit_2(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    bad = _corrupt(tmp_path)
    for args in (["eval", "/dev/zero"], ["--load", str(bad)], ["eval", str(tmp_path)]):
        code, out, err = run(capsys, *args)
        assert (code, out) == (2, ""), args
        assert err.count("\n") == 1 and err.startswith(f"tui-gym: error: {args[1]}: ")


def test_eval_of_a_fifo_through_the_console_script(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo.tgym"
    os.mkfifo(fifo)  # nobody writes to it: reading it would wait forever
    result = run_script("eval", str(fifo))
    assert (result.returncode, result.stdout) == (2, "")
    assert result.stderr == f"tui-gym: error: {fifo}: is a named pipe, not a save file\n"


class _ClosedPipe(io.TextIOWrapper):
    """A stdout whose reader is gone: every write and flush fails as on a closed pipe."""

    def __init__(self) -> None:
        super().__init__(io.BytesIO())

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        raise io.UnsupportedOperation("fileno")


@pytest.mark.parametrize(
    "args", [["envs"], ["wrappers"], ["optimal", "blackjack"], ["optimal", "gridworld", "--json"],
             ["--help"], ["train", "--help"], ["--version"], ["play", "blackjack", "--jsonl"]]
)
def test_a_closed_pipe_ends_commands_quietly(
    args: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b'{"cmd": "help"}\n')))
    try:
        code = main(args)
    except SystemExit as exit_:
        code = exit_.code
    assert code == 141
    assert capsys.readouterr().err == ""


def test_a_closed_pipe_through_the_console_script() -> None:
    read_end, write_end = os.pipe()
    os.close(read_end)  # `tui-gym wrappers | head -1`, the reader gone before the first line
    try:
        result = subprocess.run([*console_script(), "wrappers"], stdout=write_end,
                                stderr=subprocess.PIPE, timeout=120, cwd=REPO)
    finally:
        os.close(write_end)
    assert (result.returncode, result.stderr) == (141, b"")


# -- python -m tui_gym ----------------------------------------------------------


def test_python_m_tui_gym_prints_json() -> None:
    # What a command prints in this process (the listings above) it prints there too.
    result = run_module("optimal", "blackjack", "--json")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    data = json.loads(result.stdout)
    assert data["optimal_value"] == pytest.approx(-0.0466, abs=5e-5)
    assert len(data["policy"]) == 280


def test_python_m_tui_gym_errors_without_a_traceback(tmp_path: Path) -> None:
    # Every other error's one line is checked in this process (ERRORS above).
    result = run_module("eval", str(_corrupt(tmp_path)))
    assert result.returncode == 2
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    assert result.stderr.count("\n") == 1 and str(tmp_path) in result.stderr
