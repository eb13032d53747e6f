"""The command line picks the algorithm: `tui-gym algorithms`, `train --algorithm`, eval."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tui_gym.algorithms import ALGORITHMS
from tui_gym.cli import main


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_algorithms_lists_every_learner_with_its_parameters(capsys) -> None:
    code, out, _ = run(capsys, "algorithms", "--json")
    assert code == 0
    listed = {a["name"]: a for a in json.loads(out)["algorithms"]}
    assert list(listed) == [cls.name for cls in ALGORITHMS]
    dyna = {p["name"]: p for p in listed["dyna-q"]["params"]}
    assert dyna["planning_steps"]["type"] == "int" and dyna["planning_steps"]["minimum"] == 0
    assert dyna["learning_rate_schedule"]["choices"] == ["constant", "visits"]
    assert listed["monte-carlo"]["params"][-1]["name"] == "first_visit"
    code, out, _ = run(capsys, "algorithms")
    assert code == 0 and "Expected SARSA" in out and "planning_steps" in out


def test_train_with_an_algorithm_and_its_own_flag(capsys, tmp_path: Path) -> None:
    path = tmp_path / "dyna.tgym"
    code, out, err = run(capsys, "train", "gridworld", "--size", "3", "--algorithm", "Dyna_Q",
                         "--planning-steps", "3", "--episodes", "300", "--eval-episodes", "50",
                         "--save", str(path), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["algorithm"] == "dyna-q" and data["hyperparameters"]["planning_steps"] == 3
    assert data["hyperparameters"]["discount"] == 0.95  # the game's default for it
    code, out, err = run(capsys, "eval", str(path), "--episodes", "20", "--json")
    assert code == 0 and json.loads(out)["algorithm"] == "dyna-q"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--algorithm", "tabu"], "--algorithm: unknown algorithm 'tabu'; choose one of"),
        (["--planning-steps", "3"],
         "--planning-steps applies to dyna-q, dyna-q-plus, prioritized-sweeping, not q-learning"),
        (["--algorithm", "monte-carlo", "--first-visit", "maybe"],
         "--first-visit must be true or false, got 'maybe'"),
        (["--algorithm", "sarsa", "--learning-rate-schedule", "cosine"],
         "--learning-rate-schedule must be one of constant, visits"),
        (["--epsilon-start", "0.1", "--epsilon-final", "0.5"],
         "--epsilon-final (0.5) must not exceed --epsilon-start (0.1)"),
    ],
)
def test_bad_algorithm_flags_say_what_is_wrong(capsys, argv: list[str], message: str) -> None:
    code, out, err = run(capsys, "train", "blackjack", "--episodes", "10", *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and message in err, err
