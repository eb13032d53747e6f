"""The issue's promise: the default Blackjack run learns a near-optimal policy.

"With its default hyperparameters and budget, `tui-gym train blackjack` yields
a greedy policy whose exact value is within 0.005 of the optimum." The exact
value comes from dynamic programming over the card probabilities, so the
check carries no sampling noise; only the training itself is random (seeded).
"""

from __future__ import annotations

import json

import pytest

from tui_gym.algorithms import QLearning
from tui_gym.cli import main
from tui_gym.games import game_for
from tui_gym.session.session import Session, default_settings

TOLERANCE = 0.005


@pytest.mark.parametrize(
    "engine",
    [
        "auto",  # what `tui-gym train blackjack` runs: the compiled loop on the model
        # The whole default budget on the env, one step at a time: opt-in (TUI_GYM_SLOW=1).
        pytest.param("env", marks=pytest.mark.slow),
    ],
)
def test_default_blackjack_training_is_within_tolerance_of_the_optimum(
    engine: str, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["train", "blackjack", "--json", "--eval-episodes", "1000"]
    if engine != "auto":
        args += ["--engine", engine]
    code = main(args)
    out, err = capsys.readouterr()
    assert code == 0, err
    data = json.loads(out)
    assert data["engine"] == ("model" if engine == "auto" else engine)
    assert data["episodes"] == QLearning.hyperparameters().episodes  # the default budget, all of it
    evaluation = data["eval"]
    assert evaluation["optimal_value"] == pytest.approx(-0.0466, abs=5e-5)
    assert evaluation["gap"] == pytest.approx(
        evaluation["optimal_value"] - evaluation["exact_value"]
    )
    assert evaluation["gap"] <= TOLERANCE


def test_blackjack_defaults_are_undiscounted_with_visit_count_step_sizes() -> None:
    """Why these two defaults.

    - discount 1.0: the game's value (and the exact optimum it is compared with)
      is the plain expected payout of a hand. With discount < 1 the agent would
      be optimising something else: a payout one card later would look smaller,
      biasing it toward standing.
    - schedule "visits" (step max(lr, 1/n)): rewards are a noisy +-1, so the
      first estimates of each (state, action) are plain averages of what it has
      seen, which settle far faster than a small constant step would; the floor
      `learning_rate` then keeps tracking the improving values of later states.
    """
    for hp in (
        default_settings(game_for("blackjack"), "q-learning"),
        Session("blackjack").hp,
        QLearning.hyperparameters(),
    ):
        assert hp.discount == 1.0
        assert hp.learning_rate_schedule == "visits"


def test_train_says_why_a_run_ends_short_of_the_bound(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["train", "cliffwalking", "--algorithm", "sarsa", "--no-record",
                 "--eval-episodes", "10"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "It ends short of the bound (gap <= 0.13" in " ".join(out.split())
    assert "Example 6.6" in out
