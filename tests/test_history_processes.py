"""The run history used as people use it: the app in a pseudo-terminal, training with its
Compare view open and read again and again, while `train`, `compare` and `sweep` commands
record into the same file from other processes. Every run is kept, with its figures, and
the file stays sound."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import time
from pathlib import Path

from tui_gym.algorithms import QLearning
from tui_gym.core.experiments.history import RunHistory
from tui_gym.session.session import Session

from .test_app_lifecycle import Terminal, console_script

# Two waves, one after the other: between them no command has the file open, so a
# process that had lost its locks on the file would see its write-ahead log go.
WAVES = (
    (["train", "blackjack", "--episodes", "500", "--eval-episodes", "20", "--seed", "11"],
     ["compare", "blackjack", "--algorithms", "q-learning,sarsa", "--seeds", "2",
      "--episodes", "400", "--processes", "0"]),
    (["sweep", "blackjack", "--algorithm", "q-learning", "--grid", "learning_rate=0.05,0.1",
      "--seeds", "2", "--episodes", "400", "--processes", "0"],),
)
EXPECTED = {"train": 1, "compare": 2, "sweep": 2}  # runs each kind of command records


def written(db: Path) -> tuple[tuple[int, int], ...]:
    """When and how far the history and its write-ahead log were last written."""
    stats = [path.stat() for path in (db, db.with_name(db.name + "-wal")) if path.exists()]
    return tuple((s.st_mtime_ns, s.st_size) for s in stats)


def record_beside_the_app(scratch: Path) -> None:
    """The scenario once, in `scratch`; an AssertionError says what went wrong."""
    db = scratch / "runs.db"
    env = {"TUI_GYM_DB": str(db), "XDG_DATA_HOME": str(scratch / "data"),
           "XDG_STATE_HOME": str(scratch / "state"), "TUI_GYM_LOG_DIR": str(scratch / "logs")}
    script = console_script()
    agent = scratch / "long.tgym"  # a budget that lasts: the app records as long as it runs
    Session("blackjack", seed=1, hp=QLearning.hyperparameters(episodes=100_000_000)).save(agent)
    term = Terminal([script, "--load", str(agent)], env)
    commands: list[subprocess.Popen[str]] = []
    try:
        term.wait_for_text("tui-gym")
        term.type("t")
        term.wait_for_text("Hyperparameters")
        term.type(" ")
        term.wait_for_text("running")
        term.type("---")  # the slowest speed: it records all the same, and spares a core
        term.wait_for_text("animated (slow)")
        term.type("v")
        term.wait_for_text("Runs of this game")
        for wave in WAVES:
            commands = [
                subprocess.Popen([script, *argv, "--json"], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, env={**os.environ, **env})
                for argv in wave
            ]
            # The view reads the history again each time the commands have written to it,
            # while they go on writing.
            def all_done(commands: list[subprocess.Popen[str]] = commands) -> bool:
                return all(c.poll() is not None for c in commands)

            read = None
            while not all_done():
                if written(db) == read:  # nothing new to read yet
                    time.sleep(0.02)  # polling a condition: the commands run on their own
                    continue
                read = written(db)
                seen = len(term.output)
                term.type("r")
                term.wait_for(lambda seen=seen: len(term.output) > seen or all_done(), "a redraw")
            for argv, command in zip(wave, commands, strict=True):
                out, err = command.communicate()
                assert command.returncode == 0, (argv, err)
                assert "not recorded" not in err and "Traceback" not in err, (argv, err)
        term.type("q")
        assert term.exit_code() == 0, term.text[-2000:]
    finally:
        for command in commands:
            if command.poll() is None:
                command.kill()
                command.wait()
        term.close()
    assert "Traceback" not in term.text

    with RunHistory(db) as history:  # every run, as `tui-gym runs` reads them
        listing = history.read_runs()
    assert listing.damaged == ()
    runs = listing.runs
    kinds = {kind: sum(1 for r in runs if str(r.kind) == kind) for kind in (*EXPECTED, "app")}
    assert {k: kinds[k] for k in EXPECTED} == EXPECTED, kinds
    assert kinds["app"] >= 1, kinds
    for run in runs:
        assert str(run.status) == "finished", run
        assert run.figure("mean_return_last") is not None, run
    conn = sqlite3.connect(db)
    try:
        assert conn.execute("PRAGMA integrity_check").fetchall() == [("ok",)]
    finally:
        conn.close()


def test_the_app_and_three_kinds_of_command_record_into_one_history(tmp_path: Path) -> None:
    record_beside_the_app(tmp_path)
