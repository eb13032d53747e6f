"""Ending a training process: two threads that wait for one child never take it for alive.

The receiver thread reaps a child whose pipe closed while `close()` waits for the
same child in the caller's thread. The real race is rare; here the receiver's
`waitpid` is held, after it reaped the child, until the other thread has looked
(or a second has passed).
"""

from __future__ import annotations

import collections
import multiprocessing.process
import os
import threading

from tui_gym.session import process_runner

from .test_runner_and_play import wait_for

DEADLINE = 20.0


def _says_ready_and_ends(conn) -> None:
    conn.send(("ready",))
    conn.close()


def test_a_child_reaped_by_the_receiver_is_not_killed_by_close(monkeypatch) -> None:
    monkeypatch.setattr(process_runner, "child_main", _says_ready_and_ends)
    real_waitpid = os.waitpid
    receiver_reaped, looked = threading.Event(), threading.Event()
    killed: list[int | None] = []
    pid: list[int] = []

    def waitpid(who: int, flags: int) -> tuple[int, int]:
        if not pid or who != pid[0]:
            return real_waitpid(who, flags)
        if threading.current_thread().name == "tui-gym-receiver":
            result = real_waitpid(who, flags)
            receiver_reaped.set()
            looked.wait(1.0)  # the child is reaped and not yet marked so
            return result
        receiver_reaped.wait(1.0)  # (with one join at a time, this one may come first)
        return real_waitpid(who, flags)

    real_kill = multiprocessing.process.BaseProcess.kill

    def kill(process) -> None:
        killed.append(process.pid)
        looked.set()
        real_kill(process)

    monkeypatch.setattr(process_runner, "EXIT_SECONDS", DEADLINE)  # never killed for time
    monkeypatch.setattr(os, "waitpid", waitpid)
    monkeypatch.setattr(multiprocessing.process.BaseProcess, "kill", kill)
    child = process_runner._Child(collections.deque(), threading.Event())
    assert child.process.pid is not None
    pid.append(child.process.pid)
    assert wait_for(lambda: child.ready, DEADLINE)
    child.end(wait=True)
    assert not child.process.is_alive()
    assert killed == []
