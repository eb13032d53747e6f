"""The Compare view resumes an unfinished comparison (`c` on its run in the list): only the
missing tasks run, to the figures of a comparison never stopped; other settings, a finished
comparison and a run that is not a comparison are each one line.

The view is mounted alone on a small app that holds a session, over a run history in a
temporary folder.
"""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from textual.app import App, ComposeResult

from tui_gym.core.experiments import RunHistory, RunRecorder, RunSpec
from tui_gym.session.book import td
from tui_gym.session.book.figure import FigureOptions, FigureStopped, FigureTasks
from tui_gym.session.experiments.compare import CompareProgress, CompareSpec, run_compare
from tui_gym.session.session import Session
from tui_gym.ui.compare_view import CompareView

from .waiting import wait_for

SIZE = (100, 40)
SPEC = CompareSpec("blackjack", ("q-learning", "sarsa"), seeds=3, episodes=40)


class ViewApp(App[None]):
    """The Compare view alone, over one session."""

    def __init__(self, session: Session, db: Path) -> None:
        super().__init__()
        self.session = session
        self.db = db

    def compose(self) -> ComposeResult:
        yield CompareView(db=self.db, processes=0)


def stopped_after_one_task(db: Path) -> int:
    """A comparison stopped once its first task (Q-learning's seeds) landed; its first run."""
    stop = threading.Event()

    def told(progress: CompareProgress) -> None:
        if progress.tasks_done >= 1:
            stop.set()

    with RunHistory(db) as history:
        result = run_compare(SPEC, progress=told, stop=stop, history=history, processes=0)
    assert result.interrupted and result.group is not None
    return result.group


def figures(db: Path) -> list[tuple[str, float | None]]:
    with RunHistory(db) as history:
        return [(r.algorithm, f.value if (f := r.figure("mean_return_last")) else None)
                for r in sorted(history.list_runs(), key=lambda r: r.id)]


async def test_c_resumes_the_highlighted_comparison_with_only_its_missing_tasks(
        tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    group = stopped_after_one_task(db)
    with RunHistory(tmp_path / "whole.db") as history:
        run_compare(SPEC, history=history, processes=0)
    with RunHistory(db) as history:
        kept = {r.id: len(history.read_tasks(r.id)) for r in history.list_runs()}
    assert sorted(kept.values()) == [0, 1]
    app = ViewApp(Session("blackjack", seed=5), db)  # another seed: the run's are kept
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        said: list[str] = []  # every line, also one a quick job has replaced already
        say = view._say
        view._say = lambda text, error=False: (said.append(text), say(text, error))[1]
        await pilot.pause()
        lines = [str(view.run_list.get_option_at_index(i).prompt) for i in range(2)]
        assert all("interrupted, c resumes" in line for line in lines), lines
        view.run_list.highlighted = 1  # Q-learning's run: resuming it resumes its group
        await pilot.press("c")
        assert any(line.startswith(f"Resuming run #{group}: Q-learning, SARSA: 3 seeds")
                   for line in said), said
        await wait_for(pilot, lambda: view.job is None, "the comparison to end")
        assert "Comparison finished" in view.message, view.message
        assert sorted(view.run_list.selected) == sorted(kept)
        await pilot.press("c")
        assert view.message == (f"Not resumed: run {group}'s comparison finished: nothing is "
                                "missing"), view.message
    assert figures(db) == figures(tmp_path / "whole.db")
    with RunHistory(db) as history:  # the task that had landed was not run again
        assert sorted(len(history.read_tasks(i)) for i in kept) == [1, 1]


async def test_other_settings_or_a_run_of_another_kind_are_one_line(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    group = stopped_after_one_task(db)
    with RunHistory(db) as history, RunRecorder(
            history, RunSpec("train", "blackjack", "q-learning", seeds=(0,))) as run:
        run.extend("return", [-1.0, 1.0])
    app = ViewApp(Session("blackjack", seed=0, hp={"learning_rate": 0.25}), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        assert [str(r.kind) for r in view.runs] == ["train", "compare", "compare"]
        view.run_list.highlighted = 0
        await pilot.press("c")
        assert view.message == "Not resumed: run 3 is a train run: only a comparison resumes here"
        view.run_list.highlighted = 2
        await pilot.press("c")
        await wait_for(pilot, lambda: view.job is None, "the comparison to end")
        assert view.message == (
            f"Not resumed: run {group} was recorded with other settings (learning_rate 0.001 "
            "there, 0.25 here)"), view.message
        assert "\n" not in view.message
    with RunHistory(db) as history:
        assert [len(history.read_tasks(r.id)) for r in history.list_runs()
                if str(r.kind) == "compare"] in ([0, 1], [1, 0])


async def test_a_book_figures_runs_are_not_resumed_here(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    stop = threading.Event()
    with RunHistory(db) as history:
        tasks = FigureTasks(history)

        def told(*_: object) -> None:
            if tasks.played:  # the asymptotic runs have begun
                stop.set()

        with pytest.raises(FigureStopped):
            td.fig_6_6.run(FigureOptions(runs=2, episodes=20, stop=stop, tasks=tasks), told)
    app = ViewApp(Session("cliffwalking", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        assert len(view.runs) == 60
        await pilot.press("c")
        assert view.message == (
            f"Not resumed: run {tasks.group}'s runs are not one comparison of learners: resume "
            f"them with the command that started them (--resume {tasks.group})"), view.message
        assert view.job is None
