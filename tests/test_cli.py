"""The `tui-gym` command: listings, train/eval/optimal as JSON, and one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tui_gym import __version__
from tui_gym.cli import main
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
GRIDWORLD_EVAL_KEYS = EVAL_KEYS | {"success_rate", "optimal_pair_fraction"}


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


def test_wrappers_lists_the_catalog_and_the_syntax(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "wrappers")
    assert code == 0 and err == ""
    assert "--wrapper NAME:key=value" in out
    for name in CATALOG:
        assert name in out
    assert "max_episode_steps=100" in out  # parameters with their defaults


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
    assert set(evaluated) == set(data["eval"])
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
    assert set(evaluated) == set(data["eval"])
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
    assert len(policy) == 200
    assert all(set(e) == {"player_sum", "dealer_card", "usable_ace", "action"} for e in policy)
    assert {e["action"] for e in policy} == {"stick", "hit"}
    cells = {(e["player_sum"], e["dealer_card"], e["usable_ace"]) for e in policy}
    assert cells == {(s, d, u) for s in range(12, 22) for d in range(1, 11) for u in (False, True)}
    chart = {(e["player_sum"], e["dealer_card"], e["usable_ace"]): e["action"] for e in policy}
    # Basic strategy landmarks: stand on hard 17+, hit hard 12 against a 2, stand on 13 v 6.
    assert all(chart[(s, d, False)] == "stick" for s in range(17, 22) for d in range(1, 11))
    assert chart[(12, 2, False)] == "hit" and chart[(13, 6, False)] == "stick"

    sab = run_json(capsys, "optimal", "blackjack", "--sab", "--json")
    assert sab["optimal_value"] != pytest.approx(data["optimal_value"], abs=1e-4)
    assert sab["rules"]["sab"] is True and data["rules"]["sab"] is False


def test_optimal_tables_and_gridworld(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "optimal", "blackjack")
    assert code == 0 and "-0.04656" in out and "Usable ace" in out
    data = run_json(capsys, "optimal", "gridworld", "--size", "2", "--json")
    # 2x2: of the 12 ordered pairs of distinct cells, 8 are 1 step apart and 4 are 2.
    assert data["optimal_mean_steps"] == pytest.approx(16 / 12)


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
        "--learning-rate must be a number in (0, 1]",
    ),
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
    "gridworld too big": (["train", "gridworld", "--size", "50"], "size"),
    "unknown sub-command": (["frobnicate"], "'frobnicate'"),
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


# -- python -m tui_gym ----------------------------------------------------------


def test_python_m_tui_gym_lists_the_games() -> None:
    result = run_module("envs")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert "blackjack" in result.stdout and "tui_gym/GridWorld-v0" in result.stdout


def test_python_m_tui_gym_prints_json() -> None:
    result = run_module("optimal", "blackjack", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["optimal_value"] == pytest.approx(-0.0466, abs=5e-5)
    assert len(data["policy"]) == 200


def test_python_m_tui_gym_errors_without_a_traceback(tmp_path: Path) -> None:
    result = run_module("eval", str(_corrupt(tmp_path)))
    assert result.returncode == 2
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    assert result.stderr.count("\n") == 1 and str(tmp_path) in result.stderr
    bad_wrapper = run_module("train", "blackjack", "--wrapper", "Nope")
    assert bad_wrapper.returncode == 2 and "Traceback" not in bad_wrapper.stderr
    assert bad_wrapper.stderr.count("\n") == 1 and "'Nope'" in bad_wrapper.stderr
