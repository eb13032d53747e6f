"""The step panel's words: states as the game says them, each figure once, a true minus
beside the operators, counts that agree with their nouns."""

from __future__ import annotations

from types import SimpleNamespace

from tui_gym.algorithms import CellUpdate, UpdateRecord
from tui_gym.ui.widgets.step_panel import explain

EVENT = SimpleNamespace(episode=3, step=2, observation=(20, 7, 0), next_observation=(22, 7, 0))
ACTIONS = ("stick", "hit")


def describe(observation: tuple[int, int, int]) -> str:
    total, dealer, ace = observation
    return f"sum {total} vs dealer {dealer}" + (", usable ace" if ace else "")


def record(**changes: object) -> UpdateRecord:
    fields: dict[str, object] = dict(
        algorithm="q-learning", state=454, action=1, reward=-1.0, next_state=0,
        next_action=None, terminated=True, truncated=False, formula="r",
        terms=(("r", -1.0),), target=-1.0, td_error=-1.0, step_size=0.5, before=0.0,
        after=-0.5)
    fields.update(changes)
    return UpdateRecord(**fields)  # type: ignore[arg-type]


def text_of(lines: list[tuple[str, str]]) -> list[str]:
    return [f"{label} {body}".strip() for label, body in lines]


def test_a_terminal_step_says_its_target_once_with_true_minus_signs() -> None:
    lines = text_of(explain(EVENT, record(), ACTIONS, describe, "Q-learning"))
    assert "target r = −1" in lines
    assert not any(line == "r = −1" for line in lines), lines
    assert "TD error target − Q(s,a) = −1 − 0 = −1" in lines
    assert not any("-" in line for line in lines if "−" in line), lines


def test_monte_carlo_names_the_states_of_its_updates_in_words() -> None:
    updates = (CellUpdate(454, 1, -1.0, 0.5, 0.0, -0.5), CellUpdate(310, 0, -1.0, 0.5, 0.0, -0.5))
    rows = {454: (20, 7, 0), 310: (14, 2, 1)}
    lines = text_of(explain(
        EVENT, record(algorithm="monte-carlo", formula="G = r", episode_return=-1.0,
                      episode_updates=updates),
        ACTIONS, describe, "Monte Carlo control", lambda row: describe(rows[row])))
    assert "sum 20 vs dealer 7, hit: G = −1  Q 0 → −0.5" in lines
    assert "sum 14 vs dealer 2, usable ace, stick: G = −1  Q 0 → −0.5" in lines
    assert not any("s454" in line or "state 454" in line for line in lines)


def test_one_planning_update_is_one_update() -> None:
    lines = text_of(explain(EVENT, record(algorithm="dyna-q", planning_updates=1), ACTIONS,
                            describe, "Dyna-Q"))
    assert "planning then 1 simulated update from the model" in lines
