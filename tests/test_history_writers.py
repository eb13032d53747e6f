"""A run left running by a process that died reads as interrupted; one whose process lives
reads as running. Real processes, and `kill -9`."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
from pathlib import Path

from tui_gym.core.experiments import RunHistory, RunKind, RunSpec, RunStatus, list_runs
from tui_gym.core.experiments.connection import WriterCheck, current_writer
from tui_gym.ui.compare_view import describe_run

WRITER = textwrap.dedent("""
    import sys
    from tui_gym.core.experiments import RunHistory, RunSpec
    history = RunHistory(sys.argv[1])
    for kind in ("train", "app"):
        history.start_run(RunSpec(kind, "blackjack", "q-learning", seeds=(0,)))
    print("started", flush=True)
    sys.stdin.read()  # until the test ends it
""")


def test_the_runs_of_a_killed_process_read_as_interrupted(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    writer = subprocess.Popen([sys.executable, "-c", WRITER, str(db)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert writer.stdout is not None and writer.stdout.readline() == "started\n"
        runs = list_runs(str(db)).runs
        assert [r.status for r in runs] == [RunStatus.RUNNING] * 2
        app_run = next(r for r in runs if r.kind is RunKind.APP)
        assert "open in the app" in describe_run(app_run).plain
    finally:
        os.kill(writer.pid, signal.SIGKILL)
        writer.wait()
    runs = list_runs(str(db)).runs
    assert [r.status for r in runs] == [RunStatus.INTERRUPTED] * 2
    app_run = next(r for r in runs if r.kind is RunKind.APP)
    assert "interrupted" in describe_run(app_run).plain
    assert "open in the app" not in describe_run(app_run).plain


def test_a_process_that_got_the_dead_writers_id_is_not_taken_for_it(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    mark = current_writer()
    host, boot, pid, start = mark.split(" ")
    with RunHistory(db) as history:
        history.start_run(RunSpec("train", "blackjack", "q-learning"))  # this process's mark
        history.start_run(RunSpec("train", "blackjack", "sarsa"))
    conn = sqlite3.connect(db)
    with conn:  # the same id, another start: the process with this id is not the writer
        conn.execute("UPDATE runs SET writer = ? WHERE id = 2",
                     (f"{host} {boot} {pid} {int(start or 0) + 1}",))
    conn.close()
    statuses = {r.algorithm: r.status for r in list_runs(str(db)).runs}
    if start:  # where the start time is known
        assert statuses == {"q-learning": RunStatus.RUNNING, "sarsa": RunStatus.INTERRUPTED}
    else:
        assert statuses["q-learning"] is RunStatus.RUNNING


def test_marks_from_elsewhere_are_taken_at_their_word() -> None:
    check = WriterCheck()
    assert not check.gone(None) and not check.gone("")
    assert not check.gone("another-host boot 1 2")
    assert not check.gone("nonsense")
    host = current_writer().split(" ")[0]
    assert check.gone(f"{host} another-boot 1 2") == bool(current_writer().split(" ")[1])
