"""The Compare view, driven like a person would: tick runs, read the curves and the figures,
launch a comparison and stop it; a history that cannot be read is one message.

The view is mounted alone on a small app that holds a session, over a run
history in a temporary folder; waits poll a condition with a deadline.
"""

from __future__ import annotations

import re
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from textual.app import App, ComposeResult

from tui_gym.core.experiments import (
    Figure,
    RunHistory,
    RunRecorder,
    RunSpec,
    aggregate,
    mean_return_last,
)
from tui_gym.core.experiments.connection import MIGRATIONS
from tui_gym.session.experiments import compare
from tui_gym.session.experiments.compare import CompareProgress, CompareSpec
from tui_gym.session.session import Session
from tui_gym.ui import compare_job, compare_view
from tui_gym.ui.compare_job import CompareJob
from tui_gym.ui.compare_series import series_of_record
from tui_gym.ui.compare_view import CompareView, parse_count, read_launch
from tui_gym.ui.widgets.compare_chart import BRAILLE_BASE, plot_cells, value_range
from tui_gym.ui.widgets.figures_table import with_interval

from .screen import screen_text
from .waiting import press_busy, send_key, wait_busy, wait_for

DEADLINE = 20.0
SIZE = (100, 40)


@pytest.fixture(autouse=True)
def comparisons_at_the_tests_priority(monkeypatch) -> None:
    """The comparisons here run on a thread of the test's process: at the lower priority
    the app gives them, a machine loaded by other tests starves them past any wait."""
    monkeypatch.setattr(compare_job, "NICENESS", 0)


@pytest.fixture(autouse=True)
def progress_told_often(monkeypatch) -> None:
    """The comparison reports, and the view looks, several times as often as in the app: a
    wait on a live curve or a report ends sooner, with less of the comparison computed."""
    monkeypatch.setattr(compare, "PROGRESS_INTERVAL", 0.05)
    monkeypatch.setattr(compare_job, "OUTCOMES_SECONDS", 0.05)
    monkeypatch.setattr(compare_view, "POLL_SECONDS", 0.05)


class ViewApp(App[None]):
    """The Compare view alone, over one session."""

    def __init__(self, session: Session, db: Path) -> None:
        super().__init__()
        self.session = session
        self.db = db

    def compose(self) -> ComposeResult:
        yield CompareView(db=self.db)


def record_runs(db: Path) -> dict[str, int]:
    """A compare run per algorithm (5 seeds, with a band), a single train run, and a
    GridWorld run the Blackjack view must not list."""
    rng = np.random.default_rng(0)
    ids = {}
    with RunHistory(db) as history:
        for algorithm, base in (("q-learning", -0.3), ("sarsa", -0.1)):
            data = base + rng.normal(0, 0.05, (5, 200))
            with RunRecorder(history, RunSpec("compare", "blackjack", algorithm,
                                              seeds=range(5))) as run:
                for curve in aggregate(data).as_curves("return"):
                    run.put_curve(curve)
                run.add_figures(mean_return_last(data).figure("mean_return_last"))
            ids[algorithm] = run.run_id
        with RunRecorder(history, RunSpec("train", "blackjack", "q-learning", seeds=[7])) as run:
            run.extend("return", rng.normal(-0.2, 1.0, 1000))
            run.add_figures(Figure("mean_return_last", -0.21))
        ids["train"] = run.run_id
        with RunRecorder(history, RunSpec("train", "gridworld", "sarsa", seeds=[1])) as run:
            run.extend("return", rng.normal(0.5, 0.1, 50))
        ids["gridworld"] = run.run_id
    return ids


async def test_ticked_runs_draw_their_curves_and_figures(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    ids = record_runs(db)
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        # Newest first, Blackjack's only.
        assert [r.id for r in view.runs] == [ids["train"], ids["sarsa"], ids["q-learning"]]
        assert view.chart.series == ()
        assert "Tick runs" in screen_text(app)
        view.focus_default()
        await pilot.press("space", "down", "space")  # the train run, then SARSA
        await pilot.pause()
        series = view.chart.series
        assert [s.key for s in series] == [ids["train"], ids["sarsa"]]
        single, band = series
        assert not single.has_band and single.smoothing == 10  # a tenth of its 100 stored points
        assert band.has_band and np.all(band.lo <= band.mean) and np.all(band.mean <= band.hi)
        assert len(set(view.chart.colours)) == 2
        rows = view.table.rows
        assert [r.key for r in rows] == [ids["train"], ids["sarsa"]]
        assert rows[1].seeds == 5 and rows[1].mean_return_last.ci95 is not None
        assert rows[0].episodes == 1000
        text = screen_text(app)
        assert f"#{ids['sarsa']} SARSA · 5 seeds · 95% band" in text
        assert with_interval(rows[1].mean_return_last) in text
        assert chr(BRAILLE_BASE) not in text and any("⠁" <= ch <= "⣿" for ch in text)
        # Unticking takes the curve and the row away; the other keeps its colour.
        colour = view.chart.colours[1]
        await pilot.press("up", "space")
        await pilot.pause()
        assert [s.key for s in view.chart.series] == [ids["sarsa"]]
        assert view.chart.colours == (colour,)
        assert [r.key for r in view.table.rows] == [ids["sarsa"]]


@pytest.mark.parametrize("damage", ["corrupt", "newer"])
async def test_a_history_that_cannot_be_read_is_one_message(tmp_path: Path, damage: str) -> None:
    db = tmp_path / "runs.db"
    if damage == "corrupt":
        db.write_bytes(b"SQLite format 3\x00" + bytes(range(256)) * 16)
        phrase = "damaged"
    else:
        record_runs(db)
        conn = sqlite3.connect(db)
        conn.execute(f"PRAGMA user_version = {len(MIGRATIONS) + 1}")
        conn.close()
        phrase = "newer tui-gym"
    before = db.read_bytes()
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        assert view.history_error is not None
        assert view.message.startswith("The run history cannot be read:")
        assert str(db) in view.message and "\n" not in view.message
        if damage == "newer":
            assert phrase in view.message
        assert view.runs == ()
        await pilot.press("l")  # nothing is launched into a history that cannot be read
        await pilot.pause()
        assert view.job is None and "Not started" in view.message
        assert "Traceback" not in screen_text(app)
    assert db.read_bytes() == before


async def test_no_history_yet_says_so_and_creates_nothing(tmp_path: Path) -> None:
    db = tmp_path / "data" / "runs.db"
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        assert view.runs == () and view.history_error is None
        assert "No runs of Blackjack recorded yet" in view.message
    assert not db.parent.exists()


async def test_launch_fields_are_checked(tmp_path: Path) -> None:
    app = ViewApp(Session("blackjack", seed=0), tmp_path / "runs.db")
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        view.query_one("#compare-seeds").value = "ten"
        view.query_one("#compare-episodes").value = "0"
        view.query_one("#compare-episodes").focus()
        await pilot.press("enter")  # in a field, enter launches
        await pilot.pause()
        assert view.job is None
        assert view.message == (
            "Not started: Seeds: a whole number from 1 to 1,000 (got 'ten'); "
            "Episodes: a whole number from 1 to 10,000,000 (got '0')."
        )
        await pilot.press("escape")  # back to the list, where l launches
        await pilot.pause()
        assert app.focused is view.run_list


def test_launch_values() -> None:
    assert parse_count(" 1,000 ", "Seeds", 1000) == 1000
    with pytest.raises(ValueError, match=r"^Seeds: a whole number from 1 to 5 \(got nothing\)$"):
        parse_count("", "Seeds", 5)
    with pytest.raises(ValueError, match="tick at least one algorithm"):
        read_launch((), "3", "10")
    launch = read_launch(("sarsa",), "3", "10_000")
    assert (launch.algorithms, launch.seeds, launch.episodes) == (("sarsa",), 3, 10_000)
    # Digits of another script are not read as numbers, and the message says which to type.
    with pytest.raises(ValueError) as refused:
        read_launch(("sarsa",), "١٢", "٣٠٠")
    assert str(refused.value) == (
        "Seeds: a whole number from 1 to 1,000, in digits 0-9 (got '١٢'); "
        "Episodes: a whole number from 1 to 10,000,000, in digits 0-9 (got '٣٠٠')")


def test_plot_draws_the_band_under_the_line(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    ids = record_runs(db)
    with RunHistory(db) as history:
        series = series_of_record(history.get_run(ids["sarsa"]))
    assert series is not None
    bits, ink, band = plot_cells([series], 40, 8)
    assert all(any(band[row][col] == 1 for row in range(8)) for col in range(40))
    assert all(any(bits[row][col] for row in range(8)) for col in range(40))
    # Every dot of the mean lies in a cell its band shades.
    assert all(band[row][col] == 1 for row in range(8) for col in range(40) if ink[row][col] == 0)


async def test_the_chart_keeps_to_the_returns_the_game_allows_and_to_its_box(
    tmp_path: Path,
) -> None:
    db = tmp_path / "runs.db"
    rng = np.random.default_rng(1)
    # Three CliffWalking seeds of -13 (the shortest path) or -100 (the cliff) an episode:
    # their 95% band runs far above -13, which no episode can beat.
    data = rng.choice([-13.0, -100.0], size=(3, 400), p=[0.8, 0.2])
    spec = RunSpec("compare", "cliffwalking", "sarsa", seeds=range(3))
    with RunHistory(db) as history, RunRecorder(history, spec) as run:
        for curve in aggregate(data).as_curves("return"):
            run.put_curve(curve)
    app = ViewApp(Session("cliffwalking", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await pilot.pause()
        view.focus_default()
        await pilot.press("space")
        await wait_for(pilot, lambda: len(view.chart.series) == 1, "the curve")
        (series,) = view.chart.series
        assert series.bounds == (-20_000.0, -13.0)
        assert series.hi is not None and series.hi.max() <= -13.0
        low, high = value_range(view.chart.series)
        assert low < high <= -13.0
        # Each dot of the curve is drawn in its own cell of the picture, so that a viewer
        # whose font draws braille wider than a cell keeps the dots inside the chart.
        def dots() -> list[str]:
            texts = re.findall(r"<text[^>]*>([^<]*)</text>", app.export_screenshot())
            return [t for t in texts if any("⠁" <= ch <= "⣿" for ch in t)]

        await wait_for(pilot, lambda: bool(dots()), "the curve drawn at its height")
        assert all(len(t) == 1 for t in dots())


async def test_the_app_key_v_opens_it_and_another_view_stops_it(
    tmp_path: Path,
) -> None:
    from tui_gym.ui.app import TuiGymApp
    from tui_gym.ui.help_screen import HelpScreen

    db = tmp_path / "runs.db"
    ids = record_runs(db)
    app = TuiGymApp(Session("blackjack", seed=0), db=db)
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("v")
        await wait_for(pilot, lambda: app.compare_view is not None
                       and len(app.compare_view.runs) == 3, "the Compare view and its runs")
        view = app.compare_view
        view.processes = 0
        await wait_for(pilot, lambda: app.focused is view.run_list, "the list's focus")
        assert " l Launch " in screen_text(app)
        # Another view stops the comparison; what finished is recorded.
        await launch(pilot, view, {"sarsa"}, seeds=1, episodes=10_000_000)  # a curve at once
        await wait_busy(pilot, lambda: view.chart.series, "a live curve")
        send_key(pilot, "t")  # no wait for an idle process while the comparison computes
        await wait_for(pilot, lambda: view.job is None, "the comparison to stop")
        assert app.current_view == "train"
        with RunHistory(db) as history:
            newest = history.list_runs(limit=1)[0]
        assert (newest.algorithm, str(newest.status)) == ("sarsa", "interrupted")
        await pilot.press("v")
        await wait_for(pilot, lambda: newest.id in {r.id for r in view.runs}, "the new run")
        # Another game: its runs.
        await pilot.press("g")
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        await wait_for(pilot, lambda: [r.id for r in view.runs] == [ids["gridworld"]],
                       "GridWorld's runs")
        await pilot.press("question_mark")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), "the help")
        assert "Compare view" in screen_text(app)


async def launch(pilot, view: CompareView, algorithms: set[str], seeds: int, episodes: int):
    from tui_gym.ui.widgets.tick_box import TickBox

    for box in view.query(TickBox):
        box.value = box.id.removeprefix("algo-") in algorithms
    view.query_one("#compare-seeds").value = str(seeds)
    view.query_one("#compare-episodes").value = str(episodes)
    view.focus_default()
    # The comparison keeps the process busy from here on: no waiting for an idle one.
    await press_busy(pilot, "l")
    # A short comparison may be over before the first look: started, or already done.
    await wait_busy(pilot, lambda: view.job is not None or view.message.startswith("Comparison"),
                    "the comparison to start")


async def test_launch_runs_records_and_ticks_the_runs(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        view.processes = 0  # the batches on the job's thread: no child processes to start
        await pilot.pause()
        await launch(pilot, view, {"q-learning", "sarsa"}, seeds=3, episodes=40)
        await wait_for(pilot, lambda: view.job is None, "the comparison to end")
        assert "Comparison finished" in view.message
        runs = view.runs
        assert [(r.algorithm, str(r.kind), r.seeds) for r in runs] == [
            ("sarsa", "compare", (0, 1, 2)), ("q-learning", "compare", (0, 1, 2))]
        assert sorted(view.run_list.selected) == sorted(r.id for r in runs)
        assert [s.key for s in view.chart.series] == [r.id for r in runs] or [
            s.key for s in view.chart.series] == [r.id for r in reversed(runs)]
        assert all(s.has_band and s.seeds == 3 for s in view.chart.series)
        for row in view.table.rows:
            assert row.note == "" and row.episodes == 40 and row.seeds == 3
            assert row.mean_return_last.ci95 is not None
        with RunHistory(db) as history:
            recorded = history.list_runs()
        assert {str(r.status) for r in recorded} == {"finished"}
        by_id = {r.id: r for r in recorded}
        for row in view.table.rows:  # the table reads what was recorded
            assert row.mean_return_last == by_id[row.key].figure("mean_return_last")
            assert row.exact_value == by_id[row.key].figure("exact_value")


async def test_progress_draws_live_curves_and_stopping_keeps_what_finished(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        view.processes = 0
        await pilot.pause()
        # One seed: a live curve needs every seed begun (or one finished), and a job plays
        # its seeds one after another; a second seed would wait for the first's 10M episodes.
        await launch(pilot, view, {"q-learning"}, seeds=1, episodes=10_000_000)
        await wait_busy(pilot, lambda: [s.key for s in view.chart.series]
                        == [("live", "q-learning")], "a live curve")
        live = view.table.rows[0]
        assert live.note == "running" and live.seeds == 1 and live.episodes >= 1
        await wait_busy(pilot, lambda: "Q-learning (live)" in screen_text(app), "the legend")
        send_key(pilot, "s")  # no wait for an idle process while the comparison computes
        await wait_for(pilot, lambda: view.job is None, "the comparison to stop")
        assert "Comparison stopped" in view.message
        (run,) = view.runs
        assert str(run.status) == "interrupted" and view.run_list.selected == [run.id]
        (row,) = view.table.rows
        assert row.note == "interrupted" and 1 <= row.episodes < 10_000_000
        # Closing the app stops a comparison and records what finished.
        await launch(pilot, view, {"sarsa"}, seeds=2, episodes=10_000_000)
        job = view.job
        await wait_busy(pilot, lambda: job.progress_count > 0, "progress")
    assert job.done and job.error is None and job.result.interrupted
    with RunHistory(db) as history:
        assert [(r.algorithm, str(r.status)) for r in history.list_runs()] == [
            ("sarsa", "interrupted"), ("q-learning", "interrupted")]


def test_the_job_aggregates_the_live_outcomes_now_and_then_and_at_the_end(
        tmp_path: Path) -> None:
    """Each landed task reports; the outcomes (every seed aggregated) are read at most every
    `OUTCOMES_SECONDS`, and from the last report, on the comparison's thread."""
    aggregated: list[int] = []

    def run(spec, progress, **_: object) -> None:
        for done in range(1, 51):
            progress(CompareProgress(done, 50, done, 50,
                                     lambda d=done: aggregated.append(d) or (d,)))

    job = CompareJob(CompareSpec("frozenlake", ["q-learning"], 1, 10), tmp_path / "runs.db",
                     run=run, processes=0)
    job.start()
    job.close()
    assert job.progress_count == 50 and job.progress is not None and job.progress.done == 50
    assert aggregated[0] == 1 and aggregated[-1] == 50 and len(aggregated) < 10
    assert job.outcomes == (50,)


def test_seeds_times_episodes_is_bounded() -> None:
    with pytest.raises(ValueError, match=r"at most 20,000,000 .*got 30,000,000"):
        read_launch(("sarsa",), "3", "10000000")


def test_the_views_keys_leave_the_apps_keys_alone() -> None:
    from tui_gym.ui.app import TuiGymApp

    def keys(bindings) -> set[str]:
        return {k for b in bindings for k in b.key.split(",")}

    assert not keys(CompareView.BINDINGS) & keys(TuiGymApp.BINDINGS)
    assert "v" in keys(TuiGymApp.BINDINGS)
