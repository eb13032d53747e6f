"""The Train view's trace heatmap (`E`), mounted alone: a λ learner's eligibility traces of
the episode in progress, live, through either runner; a learner without traces says so."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.engine.stats import StepEvent
from tui_gym.session.session import Session
from tui_gym.ui.train_view import TrainView

from .hosts import TrainHost
from .waiting import DEADLINE, wait_until

STEPS = 8  # steps of CliffWalking's first episode at seed 0 (none ends it)


def expected_cells(session: Session, events: list[StepEvent]) -> dict[tuple[int, int], float]:
    """max over actions of e(s, a) per heatmap cell after `events`, by the book's replacing
    traces: each step sets its pair's trace to 1, then every trace decays by γλ; an
    episode's end clears them."""
    decay = session.hp.discount * session.hp["lambda"]
    traces: dict[tuple[int, int], float] = {}
    for event in events:
        traces[(int(event.observation), event.action)] = 1.0
        traces = {pair: e * decay for pair, e in traces.items()}
        if event.terminated or event.truncated:
            traces.clear()
    cells: dict[tuple[int, int], float] = {}
    for (state, _), e in traces.items():
        found = session.heatmap_cell(state)
        assert found is not None
        _, (_, row, col) = found
        cells[(row, col)] = max(cells.get((row, col), 0.0), e)
    return cells


def shown_cells(view: TrainView) -> dict[tuple[int, int], float]:
    values = np.nan_to_num(view.heatmap.panels[0].values)
    return {(int(r), int(c)): float(values[r, c]) for r, c in np.argwhere(values != 0.0)}


async def drawn(pilot, view: TrainView) -> None:
    """Wait until the heatmap shows the view's snapshot (computed off the event loop)."""
    await wait_until(pilot, lambda: view.figures_shown, "the heatmap of the snapshot")


def title(view: TrainView) -> str:
    return str(view.query_one("#train-heatmap-box").border_title)


def cliff(algorithm: str) -> Session:
    return Session("cliffwalking", algorithm=algorithm, seed=0)


async def test_e_shows_the_traces_of_the_pairs_visited_this_episode_and_back() -> None:
    session = cliff("sarsa-lambda")
    assert session.hp.traces == "replacing"
    app = TrainHost(session)
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.train_view
        trainer = session.trainer
        events = [trainer.step(explain=True) for _ in range(STEPS)]
        assert not any(event.episode_done for event in events)
        trainer.publish()
        view.show_snapshot(trainer.latest, app.runner)
        await pilot.press("E")
        await drawn(pilot, view)
        assert view.shows_traces and title(view).startswith("e(s,a)")
        assert view.heatmap.panels[0].title == "max e and the most eligible move"
        expected = expected_cells(session, events)
        shown = shown_cells(view)
        assert shown.keys() == expected.keys() and len(expected) >= 3
        for cell, e in expected.items():
            assert shown[cell] == pytest.approx(e)
        # Live: one more step, and the panel follows it.
        events.append(trainer.step(explain=True))
        trainer.publish()
        view.show_snapshot(trainer.latest, app.runner)
        await drawn(pilot, view)
        assert shown_cells(view) == pytest.approx(expected_cells(session, events))
        # The episode's end ends its traces (whole episodes, on the compiled loop).
        trainer.run(episodes=2)
        view.show_snapshot(trainer.latest, app.runner)
        await drawn(pilot, view)
        assert not trainer.episode_in_progress() and shown_cells(view) == {}
        await pilot.press("E")
        await drawn(pilot, view)
        assert not view.shows_traces and title(view) == "Q-table"
        assert view.heatmap.panels[0].title == "max Q and the greedy move"


async def test_the_toggle_outlives_a_reset_and_leaves_with_the_traces() -> None:
    session = cliff("q-learning")
    app = TrainHost(session)
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.train_view
        await pilot.press("E")
        assert not view.shows_traces and title(view) == "Q-table"
        await pilot.press("E", "E", "E")  # a burst: said once
        assert [n.message for n in app._notifications] == [
            "Q-learning keeps no eligibility traces (the λ learners do: sarsa-lambda, "
            "q-lambda, td-lambda)."]
        session.set_algorithm("q-lambda")
        view.reload()
        await pilot.press("E")
        assert view.shows_traces and title(view).startswith("e(s,a)")
        session.reset_agent()
        view.reload()
        await drawn(pilot, view)
        assert view.shows_traces and shown_cells(view) == {}
        session.set_algorithm("td-lambda")
        view.reload()
        assert view.shows_traces and title(view).startswith("e(s):")
        session.set_algorithm("sarsa")
        view.reload()
        assert not view.shows_traces and title(view) == "Q-table"
        view._no_traces_until = 0.0  # as when the first notice has gone
        await pilot.press("E")
        notices = [n.message for n in app._notifications]  # the first may have timed out
        assert not view.shows_traces and "SARSA keeps no eligibility traces" in notices[-1]


async def test_td_lambda_shows_the_trace_of_each_state_and_none_after_the_episode() -> None:
    session = Session("random-walk", algorithm="td-lambda", seed=0)
    app = TrainHost(session)
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.train_view
        trainer = session.trainer
        trainer.run(episodes=3)  # the compiled loop; each episode's traces end with it
        assert not trainer.episode_in_progress()
        view.show_snapshot(trainer.latest, app.runner)
        await pilot.press("E")
        await drawn(pilot, view)
        assert title(view).startswith("e(s):") and shown_cells(view) == {}
        event = trainer.step(explain=True)
        assert not event.episode_done
        trainer.publish()
        view.show_snapshot(trainer.latest, app.runner)
        await drawn(pilot, view)
        found = session.heatmap_cell(event.observation)
        assert found is not None
        _, (_, row, col) = found
        assert shown_cells(view) == {(row, col): 1.0}  # e(s) = γλ·0 + 1, the state just left


async def test_the_process_runner_ships_the_traces_step_by_step_and_at_max_speed() -> None:
    session = cliff("sarsa-lambda")
    app = TrainHost(session, runner="process")
    async with app.run_test(size=(120, 40)) as pilot:
        view, runner = app.train_view, app.runner
        await pilot.press("E")
        events = []
        for _ in range(STEPS):
            assert runner.run_one_step()
            await wait_until(pilot, lambda: runner.wait_idle(0), "the step in the child")
            events.append(runner.last_event)
        view.show_snapshot(runner.latest, runner)
        await drawn(pilot, view)
        assert shown_cells(view) == pytest.approx(expected_cells(session, events))
        assert runner.start()  # at max speed, the default
        await wait_until(pilot, lambda: runner.latest.episodes >= 5, "episodes in the child")
        snapshot = runner.latest
        view.show_snapshot(snapshot, runner)
        await drawn(pilot, view)
        assert snapshot.traces is not None and snapshot.traces.max() <= 1.0
        assert view.heatmap.panels[0].title == "max e and the most eligible move"
        runner.pause(wait=False)
        assert runner.wait_idle(DEADLINE)
        view.show_snapshot(runner.latest, runner)
        np.testing.assert_array_equal(runner.latest.traces, session.agent.eligibility())
        assert view.shows_traces
