"""A comparison's child processes never outlive the command that started them.

Real processes: `tui-gym compare` long enough to spread its seeds over child
processes, then its end by SIGKILL, SIGTERM or Ctrl+C (SIGINT). The children
have process groups of their own, and are gone soon after the command; on every
signal it can catch, the command stops cleanly and records its runs as
interrupted. SIGHUP takes SIGTERM's handler: that it does is checked in this
process.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from tui_gym.core.engine.processes import stops_on_signals
from tui_gym.core.experiments.history import RunHistory

from .test_runner_and_play import wait_for

DEADLINE = 60.0


def _children(pid: int) -> list[int]:
    """The processes whose parent is `pid`: the children the kernel lists for each of its
    threads (polled often: reading every process's stat each time kept a core busy)."""
    found = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            found += [int(child) for child in (task / "children").read_text().split()]
        except OSError:
            continue
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _group(pid: int) -> int | None:
    """The process group of `pid` (None once it is gone)."""
    try:
        return os.getpgid(pid)
    except ProcessLookupError:
        return None


def _start(db: Path) -> subprocess.Popen[str]:
    env = {**os.environ, "TUI_GYM_DB": str(db)}
    return subprocess.Popen(
        [sys.executable, "-m", "tui_gym", "compare", "taxi", "--algorithms",
         "q-learning,sarsa", "--seeds", "8", "--episodes", "200000", "--processes", "2",
         "--json", "--db", str(db)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )


def _statuses(db: Path) -> set[str]:
    """The recorded runs' statuses, as `tui-gym runs` reads them."""
    with RunHistory(db) as history:
        found = history.read_runs()
    assert not found.damaged, found.damaged
    return {str(run.status) for run in found.runs}


@pytest.mark.parametrize("kind", ["SIGKILL", "SIGTERM", "SIGINT"])
def test_the_children_end_with_the_command(kind: str, tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    command = _start(db)
    try:
        assert wait_for(lambda: len(_children(command.pid)) >= 2, DEADLINE), (
            command.stderr.read() if command.poll() is not None else "no children")
        children = [pid for pid in _children(command.pid) if _alive(pid)]
        assert wait_for(lambda: all(_group(pid) in (pid, None) for pid in children), DEADLINE)
        command.send_signal(getattr(signal, kind))
        assert wait_for(lambda: not any(_alive(pid) for pid in children), DEADLINE)
        command.wait(timeout=DEADLINE)
    finally:
        if command.poll() is None:
            command.kill()
            command.wait()
    if kind == "SIGKILL":
        assert command.returncode == -signal.SIGKILL
        return
    assert command.returncode == 130, command.stderr.read()
    assert _statuses(db) == {"interrupted"}


def test_sighup_and_sigterm_stop_a_run_alike() -> None:
    # The handlers go in on the main thread only: elsewhere the signal would end pytest.
    assert threading.current_thread() is threading.main_thread()
    for kind in (signal.SIGTERM, signal.SIGHUP):
        before = signal.getsignal(kind)
        stop = threading.Event()
        with stops_on_signals(stop):
            os.kill(os.getpid(), kind)
            assert stop.wait(DEADLINE), kind.name
        assert signal.getsignal(kind) is before
