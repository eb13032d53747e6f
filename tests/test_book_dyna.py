"""The book's figures of chapter 8 after 8.2: the changing mazes (the world changing phase
after phase under one learner, the measures read off the cumulative reward) and Example 8.4
(finer mazes, updates counted until optimal), each figure's claims at a few runs with bounds
from the run count."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import algorithm
from tui_gym.core.engine import loop
from tui_gym.core.mdp import solve, with_horizon
from tui_gym.session.book import dyna, figure_named, figures
from tui_gym.session.book.figure import BookFigure, FigureOptions, heading
from tui_gym.session.book.runs import Played, play_steps
from tui_gym.session.experiments.compare import Arm

FIGURE = BookFigure("x", "a test figure", "", "blocking-maze", lambda *_: None, runs=3)


def test_the_world_changes_under_the_learner_at_its_step() -> None:
    dyna_q = Arm("dyna-q", dyna.MAZE_SETTINGS, "Dyna-Q")
    (played,) = play_steps(FIGURE, "blocking-maze", (dyna_q,), FigureOptions(seed=3),
                           lambda *_: None, 1600, game_params={"change_at": 1000})
    assert played.values.shape == (3, 1600)
    assert (np.diff(played.values, axis=1) >= 0).all()
    every = dyna.episodes_after(played, 0)
    after = dyna.episodes_after(played, 1000)
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
    assert dyna.reward_between(played, 5, 12).tolist() == [2.0, 0.0]
    assert [x.tolist() for x in dyna.episodes_after(played, 3)] == [[4, 5], []]
    assert dyna.found_after(played, 4).tolist() == [8.0, 11.0]


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
    plain = {**dyna.MAZE_SETTINGS, "kappa": 0.0}
    monkeypatch.setattr(dyna, "MAZE_LEARNERS",
                        (dyna.MAZE_LEARNERS[0], Arm("dyna-q-plus", plain, "Dyna-Q+")))
    result = figure_named("8.5").run(FigureOptions(runs=8, seed=100), lambda *_: None)
    verdicts = {c.claim.split(":")[0]: c.ok for c in result.checks}
    assert not verdicts["Dyna-Q+ finds it"]
    assert not verdicts["after the change Dyna-Q+'s curve is steeper"]


# --- Example 8.4: prioritized sweeping against Dyna-Q on finer mazes ---------------------


@pytest.mark.parametrize("scale", [1, 2, 3])
def test_a_finer_dyna_maze_has_the_same_walls_in_finer_cells(scale: int) -> None:
    from tui_gym.envs.dyna_maze import maze_phases

    ((_, grid),) = maze_phases("dyna", scale=scale)
    assert (grid.rows, grid.cols) == (6 * scale, 9 * scale)
    assert len(grid.walls) == 7 * scale**2
    assert grid.terminals == ((0, 9 * scale - 1),) and grid.start == (2 * scale, 0)
    model, _, _, cells = dyna._maze(scale, 1, 0)
    assert model.n_states == 54 * scale**2 and cells == 47 * scale**2


def test_prioritized_sweepings_log_adds_up_its_updates() -> None:
    model, _, hps, _ = dyna._maze(1, 1, 0)
    arrays = loop.ModelArrays.of(model)
    cls = algorithm("prioritized-sweeping")

    def played(steps_a_call: int) -> tuple[int, np.ndarray]:
        agent = cls(4, cls.settings(hps[1]), n_states=model.n_states, seed=5)
        cursor, out, log = loop.Cursor(), np.zeros((50, loop.COLUMNS)), np.zeros((1, 8))
        counted = 0
        for _ in range(600 // steps_a_call):
            loop.play(agent, arrays, cursor, 50, steps_a_call, out, log)
            counted += int(log[0, 1]) if steps_a_call == 1 else 0
        return (counted if steps_a_call == 1 else int(log[0, 7])), agent.q.copy()

    one_by_one, q = played(1)
    at_once, same_q = played(600)
    assert one_by_one == at_once > 0
    np.testing.assert_array_equal(q, same_q)


def test_an_agent_is_optimal_once_every_greedy_move_is_on_a_shortest_way() -> None:
    model, good, _, _ = dyna._maze(1, 1, 0)
    start = int(np.flatnonzero(model.initial)[0])
    steps = model.replace(reward=np.full(model.reward.shape, -1.0), reward_std=None)
    q = solve(with_horizon(steps, None)).q
    assert dyna._optimal(q, model, good, start)
    ties = q.copy()
    ties[start] = ties[start].max()  # every move from the start looks as good
    assert not dyna._optimal(ties, model, good, start)
    assert not dyna._optimal(np.zeros_like(q), model, good, start)


def test_example_8_4s_claims_at_a_few_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(dyna, "SCALES", (1, 2))
    result = figure_named("example 8.4").run(FigureOptions(runs=5, seed=100),
                                             lambda *_: None)
    assert result.runs == 5 and len(result.checks) == 4
    assert result.ok, [c for c in result.checks if not c.ok]
    assert [s.x.tolist() for s in result.series] == [[47.0, 188.0]] * 2


def test_dyna_q_against_itself_shows_no_advantage(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(dyna, "SCALES", (1,))
    dyna_q = dyna.SWEEPERS[0]
    monkeypatch.setattr(dyna, "SWEEPERS", (dyna_q, Arm("dyna-q", dyna_q.settings, "again")))
    result = dyna.example_8_4.run(FigureOptions(runs=5, seed=100), lambda *_: None)
    assert [c.ok for c in result.checks] == [False, False]


def test_an_example_is_listed_in_its_chapter_and_called_by_its_name() -> None:
    names = [f.name for f in figures()]
    assert names[names.index("8.2"):names.index("8.2") + 4] == [
        "8.2", "8.4", "8.5", "example 8.4"]
    assert figure_named("Example 8.4") is figure_named("e8.4") is dyna.example_8_4
    assert heading("example 8.4") == "Example 8.4" and heading("8.4") == "Figure 8.4"
