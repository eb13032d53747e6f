"""The command line's contracts: every flag says what it does and reads numbers as `Param`s
do, and every `--json` object carries its `schema` version and exactly the keys the README
lists for its command."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

import pytest

from tui_gym.cli import build_parser, main
from tui_gym.cli.main import json_flags
from tui_gym.cli.output import JSON_SCHEMAS

README = Path(__file__).resolve().parents[1] / "README.md"


def _parsers(
    parser: argparse.ArgumentParser, path: str = "tui-gym"
) -> list[tuple[str, argparse.ArgumentParser]]:
    found = [(path, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += _parsers(sub, f"{path} {name}")
    return found


def test_every_flag_and_sub_command_says_what_it_does() -> None:
    missing = []
    for path, parser in _parsers(build_parser()):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                missing += [f"{path} {choice.dest}" for choice in action._choices_actions
                            if not choice.help]
            elif not action.help or action.help == argparse.SUPPRESS:
                missing.append(f"{path} {'/'.join(action.option_strings) or action.dest}")
    assert missing == []


def test_every_number_flag_reads_ascii_digits_only() -> None:
    # Python's int() and float() read any script's digits: '\u0661\u0662' is 12 to them.
    loose = [f"{path} {'/'.join(action.option_strings) or action.dest}"
             for path, parser in _parsers(build_parser()) for action in parser._actions
             if action.type in (int, float)]
    assert loose == []


def test_every_json_command_has_a_schema_and_its_help_says_so(
    capsys: pytest.CaptureFixture[str],
) -> None:
    parser = build_parser()
    flags = json_flags(parser)
    # `runs --recover --json` and `book --json` without a figure give a shape of their own.
    assert set(flags) == set(JSON_SCHEMAS) - {"runs recover", "book list"}
    for command, flag in flags.items():
        assert f'"schema": {JSON_SCHEMAS[command]}' in (flag.help or ""), command
    listing = " ".join(parser.format_help().split())
    assert ", ".join(flags) + " take --json" in listing


def _readme_rows() -> dict[str, tuple[int, set[str]]]:
    """The README's JSON outputs table: per command, its schema and the keys it names."""
    text = README.read_text(encoding="utf-8")
    section = text[text.index("## JSON outputs"):]
    section = section[: section.index("\n## ")]
    rows, cells = {}, {}
    for line in section.splitlines():
        found = re.fullmatch(r"\| `([a-z ]+)` \| (\d+) \| (.*) \|", line)
        if found:
            cells[found[1]] = found[3]
            rows[found[1]] = (int(found[2]), set(re.findall(r"`(\w+)`", found[3])))
    for command, cell in cells.items():  # "a run as in `runs`": that row's keys too
        for other in re.findall(r"as in `([a-z ]+)`", cell):
            rows[command][1].update(rows[other][1])
    return rows


def test_the_readme_gives_every_command_its_schema() -> None:
    rows = _readme_rows()
    assert {command: schema for command, (schema, _) in rows.items()} == JSON_SCHEMAS


# --- each command's keys, pinned ----------------------------------------------------------


def run_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    code = main(list(args))
    out, err = capsys.readouterr()
    assert code == 0, err
    lines = out.splitlines()
    assert len(lines) == 1
    data = json.loads(lines[0])
    assert list(data)[0] == "schema"
    return data


def pinned(command: str, data: dict[str, Any], keys: set[str]) -> None:
    """`data` is `command`'s object with its version and exactly `keys`, which the README
    names in the command's row."""
    assert data["schema"] == JSON_SCHEMAS[command]
    assert set(data) == {"schema"} | keys
    documented = _readme_rows()[command][1]
    assert keys <= documented, keys - documented


PARAM = {"name", "type", "default", "minimum", "maximum", "range", "help"}
SUMMARY = {"id", "kind", "game", "algorithm", "seeds", "status", "started_at", "ended_at",
           "seconds", "group", "figures"}
FIGURE = {"name", "value", "unit", "ci95"}
OUTCOME = {"seeds_done", "episodes_done", "mean_return_last", "ci95", "exact_value",
           "exact_gap", "rms_error", "rms_ci95", "rms_curve", "run_id", "curve"}
EVAL = {"env_id", "algorithm", "episodes", "episodes_requested", "mean_return", "std_return",
        "win_rate", "draw_rate", "loss_rate", "exact_value", "optimal_value", "gap"}
BENCHMARK = {
    "game", "env_id", "params", "wrappers", "player", "episodes", "seeds", "decision_timeout",
    "allow_hints", "mean_return", "return_ci95", "mean_regret", "regret_ci95", "regret_note",
    "decisions", "agreement", "invalid_actions", "timeouts", "defaulted", "bad_requests",
    "hints_refused", "decision_ms_median", "decision_ms_p95", "player_status", "player_stderr",
    "seconds", "run_id",
}


def test_envs_keys(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "envs", "--json")
    pinned("envs", data, {"envs"})
    for game in data["envs"]:
        assert set(game) == {"name", "env_id", "other_ids", "key", "actions", "description",
                             "teaches", "params"}
        assert all(set(p) - {"choices"} == PARAM for p in game["params"])


def test_wrappers_keys(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "wrappers", "--json")
    pinned("wrappers", data, {"wrappers", "syntax"})
    for wrapper in data["wrappers"]:
        assert set(wrapper) == {"name", "summary", "changes_observation", "params"}
        assert all(set(p) == PARAM for p in wrapper["params"])


def test_maps_keys(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    shape = {"size", "games", "goal_reachable", "text"}
    listing = run_json(capsys, "maps", "--json")
    pinned("maps", listing, {"maps"})
    assert all(set(m) == {"name", "description"} | shape for m in listing["maps"])
    pinned("maps", run_json(capsys, "maps", "4x4", "--json"), {"name"} | shape)
    pinned("maps", run_json(capsys, "maps", "--random", "3x3", "--json"), {"name"} | shape)
    path = tmp_path / "map.txt"
    path.write_text("SF\nFG\n")
    pinned("maps", run_json(capsys, "maps", "--check", str(path), "--json"), {"path"} | shape)


def test_algorithms_keys(capsys: pytest.CaptureFixture[str]) -> None:
    data = run_json(capsys, "algorithms", "--json")
    pinned("algorithms", data, {"algorithms"})
    for learner in data["algorithms"]:
        assert set(learner) == {"name", "title", "summary", "target", "params"}
        for param in learner["params"]:
            choice = {"name", "type", "default", "choices", "range", "help"}
            assert set(param) in (PARAM, choice)


def test_train_and_eval_keys(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path, db = tmp_path / "bj.tgym", tmp_path / "runs.db"
    train = {"env_id", "env_kwargs", "algorithm", "wrappers", "engine", "engine_reason",
             "episodes", "steps", "seconds", "episodes_per_second", "hyperparameters",
             "rolling_mean_return", "eval", "saved", "run"}
    data = run_json(capsys, "train", "blackjack", "--episodes", "50", "--eval-episodes", "10",
                    "--save", str(path), "--db", str(db), "--json")
    pinned("train", data, train)
    assert set(data["eval"]) == EVAL
    targeted = run_json(capsys, "train", "blackjack", "--episodes", "50", "--eval-episodes",
                        "10", "--target-gap", "0.5", "--no-record", "--json")
    pinned("train", targeted, train | {"target_gap", "reached_target", "checked_gap"})
    pinned("eval", run_json(capsys, "eval", str(path), "--episodes", "10", "--json"), EVAL)
    walk = {key for key in train if key != "eval"} | {"eval", "rms_error", "prediction"}
    predicted = run_json(capsys, "train", "random-walk", "--algorithm", "td0", "--episodes",
                         "20", "--eval-episodes", "5", "--no-record", "--json")
    pinned("train", predicted, walk)
    assert set(predicted["prediction"]) == {"states", "estimate", "truth"}
    unscored = run_json(capsys, "train", "random-walk", "--algorithm", "td0", "--episodes",
                        "5", "--eval-episodes", "5", "--wrapper", "TimeAwareObservation",
                        "--no-record", "--json")
    pinned("train", unscored, walk - {"prediction"} | {"rms_reason"})
    assert unscored["rms_error"] is None


def test_optimal_keys(capsys: pytest.CaptureFixture[str]) -> None:
    base = {"env_id", "env_kwargs", "optimal_value", "meaning", "policy"}
    data = run_json(capsys, "optimal", "frozenlake", "--json")
    pinned("optimal", data, base)
    assert all(set(row) == {"state", "actions", "value"} for row in data["policy"])
    pinned("optimal", run_json(capsys, "optimal", "gridworld", "--size", "2", "--json"),
           base | {"optimal_mean_steps"})


def test_runs_keys(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    db = str(tmp_path / "runs.db")
    run_json(capsys, "train", "blackjack", "--episodes", "50", "--eval-episodes", "10",
             "--db", db, "--json")
    listing = run_json(capsys, "runs", "--db", db, "--json")
    pinned("runs", listing, {"db", "runs", "damaged", "total"})
    (run,) = listing["runs"]
    assert set(run) == SUMMARY and all(set(f) == FIGURE for f in run["figures"])
    shown = run_json(capsys, "runs", "show", str(run["id"]), "--db", db, "--json")
    pinned("runs show", shown, SUMMARY | {"game_params", "wrappers", "hyperparameters",
                                          "versions", "agent_path", "curves"})
    assert all(set(c) == {"name", "episodes", "values"} for c in shown["curves"])
    exported = run_json(capsys, "runs", "export", str(run["id"]), "--csv",
                        str(tmp_path / "run.csv"), "--db", db, "--json")
    pinned("runs export", exported, {"run", "path", "columns", "rows"})
    recovered = run_json(capsys, "runs", "--recover", "--db", db, "--json")
    pinned("runs recover", recovered,
           {"source", "target", "copied", "unreadable", "curves_dropped", "check"})
    removed = run_json(capsys, "runs", "rm", str(run["id"]), "--db", db, "--json")
    pinned("runs rm", removed, {"db", "removed"})
    assert set(removed["removed"]) == SUMMARY
    pruned = run_json(capsys, "runs", "prune", "--db", db, "--json")
    pinned("runs prune", pruned, {"db", "runs", "tasks"})


def test_compare_and_sweep_keys(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    db = str(tmp_path / "runs.db")
    common = ("--seeds", "2", "--episodes", "20", "--processes", "0", "--db", db, "--json")
    compared = run_json(capsys, "compare", "blackjack", "--algorithms", "q-learning,sarsa",
                        *common)
    pinned("compare", compared, {"game", "episodes", "seeds", "first_seed", "optimum",
                                 "interrupted", "group", "tasks", "results"})
    assert compared["tasks"] == {"done": 2, "total": 2}
    for result in compared["results"]:
        assert set(result) == {"algorithm", "hyperparameters"} | OUTCOME
        assert all(set(p) == {"episode", "mean", "lo", "hi"} for p in result["curve"])
    swept = run_json(capsys, "sweep", "blackjack", "--algorithm", "q-learning", "--grid",
                     "learning_rate=0.1,0.2", *common)
    pinned("sweep", swept, {"game", "algorithm", "episodes", "seeds", "first_seed", "grid",
                            "sample", "tasks", "hyperparameters", "optimum", "interrupted",
                            "group", "points"})
    assert all(set(point) == {"values", "rank"} | OUTCOME for point in swept["points"])
    sampled = run_json(capsys, "sweep", "blackjack", "--algorithm", "q-learning", "--sample",
                       "2", "--range", "learning_rate=0.01:1:log", *common)
    assert set(sampled["sample"]) == {"n", "seed", "ranges"}
    assert sampled["sample"]["ranges"]["learning_rate"] == {"low": 0.01, "high": 1.0,
                                                            "log": True}
    assert sorted(p["rank"] for p in sampled["points"]) == [1, 2]


def test_screenshots_keys(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import tui_gym.ui.screenshots as screenshots

    monkeypatch.setattr(screenshots, "write_screenshots", lambda directory: [tmp_path / "a.svg"])
    pinned("screenshots", run_json(capsys, "screenshots", str(tmp_path), "--json"), {"written"})


def test_bench_keys(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import tui_gym.bench.run

    from .test_bench import fake_results

    monkeypatch.setattr(tui_gym.bench.run, "run_bench", lambda **kwargs: fake_results())
    data = run_json(capsys, "bench", "--quick", "--json")
    pinned("bench", data, _readme_rows()["bench"][1])


def test_benchmark_keys(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    db = str(tmp_path / "runs.db")
    result = run_json(capsys, "benchmark", "blackjack", "--agent", "random", "--episodes", "5",
                      "--db", db, "--json")
    pinned("benchmark", result, BENCHMARK)
    board = run_json(capsys, "benchmark", "blackjack", "--leaderboard", "--db", db, "--json")
    pinned("benchmark", board, {"game", "db", "runs"})
    assert all(set(run) == {"rank"} | SUMMARY for run in board["runs"])


def test_plan_and_book_keys(capsys: pytest.CaptureFixture[str]) -> None:
    planned = run_json(capsys, "plan", "corner-grid", "--method", "value-iteration", "--json")
    pinned("plan", planned, {"game", "env_kwargs", "method", "start", "gamma", "theta",
                             "in_place", "converged", "sweeps", "iterations", "start_value",
                             "limited_value", "episode_limit", "values", "policy"})
    assert set(planned["values"][0]) == {"state", "value"}
    assert set(planned["policy"][0]) == {"state", "actions"}
    listed = run_json(capsys, "book", "--json")
    pinned("book list", listed, {"figures"})
    assert set(listed["figures"][0]) == {"figure", "title", "world", "about", "runs",
                                         "episodes"}
    figure = run_json(capsys, "book", "3.2", "--json")
    pinned("book", figure, {"figure", "title", "runs", "series", "checks"})
    assert all(set(s) == {"label", "x", "y", "lo", "hi"} for s in figure["series"])
    assert all(set(c) == {"claim", "book", "measured", "ok"} for c in figure["checks"])
