"""The book's figures of chapter 8's changing mazes: the world changing phase after phase
under one learner, the measures read off the cumulative reward, and each figure's claims at a
few runs with bounds from the run count."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.session.book import changing_mazes, figure_named
from tui_gym.session.book.figure import BookFigure, FigureOptions
from tui_gym.session.book.runs import Learner, Played, play_steps

FIGURE = BookFigure("x", "a test figure", "", "blocking-maze", lambda *_: None, runs=3)


def test_the_world_changes_under_the_learner_at_its_step() -> None:
    dyna = Learner("Dyna-Q", "dyna-q", changing_mazes.SETTINGS)
    (played,) = play_steps(FIGURE, "blocking-maze", (dyna,), FigureOptions(seed=3),
                           lambda *_: None, 1600, game_params={"change_at": 1000})
    assert played.values.shape == (3, 1600)
    assert (np.diff(played.values, axis=1) >= 0).all()
    every = changing_mazes.episodes_after(played, 0)
    after = changing_mazes.episodes_after(played, 1000)
    # The 10-step way is taken before the wall moves (a run may still be walking at random
    # in the bottom rows); after, no episode is shorter than 16.
    assert sum((lengths[: len(lengths) - len(later)] < 16).any()
               for lengths, later in zip(every, after, strict=True)) == 2
    assert all(later.size == 0 or later.min() >= 16 for later in after)


def test_the_measures_read_off_the_cumulative_reward() -> None:
    # One run reaching the goal at steps 3, 7 and 12; another never.
    rewards = np.zeros((2, 15))
    rewards[0, [2, 6, 11]] = 1.0
    played = Played("x", np.cumsum(rewards, axis=1), None, None)
    assert changing_mazes.reward_between(played, 5, 12).tolist() == [2.0, 0.0]
    assert [x.tolist() for x in changing_mazes.episodes_after(played, 3)] == [[4, 5], []]
    assert changing_mazes.found_after(played, 4).tolist() == [8.0, 11.0]


# Dyna-Q finds the blocking maze's new way in some runs only: its curve's rise needs more.
@pytest.mark.parametrize(("name", "runs"), [("8.4", 30), ("8.5", 8)])
def test_the_books_claims_at_a_few_runs(name: str, runs: int) -> None:
    seen: list[tuple[int, int]] = []
    result = figure_named(name).run(FigureOptions(runs=runs, seed=100),
                                    lambda done, total, _: seen.append((done, total)))
    assert result.runs == runs and len(result.checks) >= 5
    assert result.ok, [c for c in result.checks if not c.ok]
    assert seen and seen[-1][0] == seen[-1][1]
    assert [s.label for s in result.series] == ["Dyna-Q", "Dyna-Q+"]


def test_without_its_bonus_dyna_q_plus_misses_the_shortcut(
        monkeypatch: pytest.MonkeyPatch) -> None:
    plain = {**changing_mazes.SETTINGS, "kappa": 0.0}
    monkeypatch.setattr(changing_mazes, "LEARNERS",
                        (changing_mazes.LEARNERS[0], Learner("Dyna-Q+", "dyna-q-plus", plain)))
    result = figure_named("8.5").run(FigureOptions(runs=8, seed=100), lambda *_: None)
    verdicts = {c.claim.split(":")[0]: c.ok for c in result.checks}
    assert not verdicts["Dyna-Q+ finds it"]
    assert not verdicts["after the change Dyna-Q+'s curve is steeper"]
