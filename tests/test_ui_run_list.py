"""How the Compare view lists runs: an app's run whose agent is still there is open, not
running; text from the history is shown as data; a run that does not read is named in the
view's message while the others are listed and drawn."""

from __future__ import annotations

import sqlite3
from pathlib import Path

from tui_gym.core.experiments import RunHistory, RunRecorder, RunSpec
from tui_gym.session.session import Session
from tui_gym.ui.compare_view import CompareView, describe_run

from .screen import screen_text
from .test_history_rows import IN_THE_RECORD, edit, record_three
from .test_ui_compare import SIZE, ViewApp
from .waiting import wait_for


def test_an_open_app_run_reads_open_and_a_running_train_run_reads_running(
    tmp_path: Path,
) -> None:
    with RunHistory(tmp_path / "runs.db") as history:
        for kind in ("app", "train", "compare"):
            history.start_run(RunSpec(kind, "blackjack", "q-learning", seeds=(0,)))
        with RunRecorder(history, RunSpec("app", "blackjack", "sarsa", seeds=(0,))):
            pass  # ended: the app let its agent go
        lines = {(run.kind, run.algorithm): describe_run(run).plain
                 for run in history.list_runs()}
    assert " · open in the app · " in lines[("app", "q-learning")]
    assert "running" not in lines[("app", "q-learning")]
    assert " · running · " in lines[("train", "q-learning")]
    assert " · running · " in lines[("compare", "q-learning")]
    assert "open" not in lines[("app", "sarsa")] and "running" not in lines[("app", "sarsa")]


async def test_text_from_the_history_is_shown_as_data(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    hostile = "[/bold]q\x1b]2;PWNED\x1b\\\x1b]52;c;SGVsbG8=\x07"
    with RunHistory(db) as history, RunRecorder(
        history, RunSpec("train", "blackjack", hostile, seeds=(0,))
    ) as run:
        run.extend("return", [0.5, -1.0, 1.0])
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await wait_for(pilot, lambda: len(view.runs) == 1, "the run listed")
        view.focus_default()
        await pilot.press("space")
        await wait_for(pilot, lambda: len(view.table.rows) == 1, "the run drawn")
        shown = [str(view.run_list.get_option_at_index(0).prompt),
                 view.table.rows[0].label, *(s.label for s in view.chart.series)]
        text = screen_text(app)
    for line in (*shown, text):
        assert "\x1b" not in line and "\x07" not in line
    assert "\\x1b]2;PWNED" in shown[0] and "[/bold]" in shown[0]


async def test_runs_that_do_not_read_are_named_and_the_others_drawn(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    record_three(db)
    edit(db, "UPDATE runs SET started_at = 'abc' WHERE id = 1")
    edit(db, *IN_THE_RECORD["10 bytes claiming 300,000,000 points"])  # run 2's curves
    app = ViewApp(Session("blackjack", seed=0), db)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(CompareView)
        await wait_for(pilot, lambda: len(view.runs) == 2, "the readable runs listed")
        assert [r.id for r in view.runs] == [3, 2]
        assert view.message.startswith("Run 1 cannot be read: its start is not a time")
        assert "tui-gym runs rm 1" in view.message and "\n" not in view.message
        view.focus_default()
        await pilot.press("space", "down", "space")  # run 3, then run 2, whose curves are bad
        await wait_for(pilot, lambda: view.message.startswith("Run 2 in "), "run 2 named")
        assert "cannot be read: its curves do not decode" in view.message
        assert [r.key for r in view.table.rows] == [3]
        await pilot.press("r")  # read again: the same, and the view goes on
        await pilot.pause()
        assert [r.id for r in view.runs] == [3, 2] and view.message.startswith("Run ")
        assert "Traceback" not in screen_text(app)
    conn = sqlite3.connect(db)
    assert conn.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 3  # nothing changed
    conn.close()
