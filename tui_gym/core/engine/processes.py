"""Child processes that never outlive the process that started them.

`context()` is how children start: fork on Linux (the quickest, and a child
inherits the learners compiled so far), spawn elsewhere. A child calls
`watch_parent(pid)` first: it gets a process group of its own (a Ctrl+C in
the terminal reaches the parent alone, which decides how a run ends), asks
the kernel to kill it when its parent dies (`PR_SET_PDEATHSIG` on Linux), and
a watcher thread ends it as soon as its parent is gone (everywhere, and for
a parent that died before the request). The parent ends its children on
every way out: `end(process)` kills a child's whole group, and
`stops_on_signals(stop)` turns SIGTERM and SIGHUP into the run's stop flag
while it runs on the main thread, so those end a run as cleanly as Ctrl+C.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any

__all__ = ["context", "end", "stops_on_signals", "watch_parent"]

_PR_SET_PDEATHSIG = 1
WATCH_SECONDS = 0.2  # how often a child looks whether its parent is still there


def context() -> Any:
    """Fork on Linux, else spawn (see the module docstring). The children only run
    learners (no terminal, no locks of the parent's threads), so forking from a program
    with threads (the app) is safe here."""
    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("spawn")


def watch_parent(parent: int) -> None:
    """In a child: a process group of its own, and an end as soon as `parent` is gone."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides how Ctrl+C ends a run
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # it died before the request
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_SECONDS)
        os._exit(1)

    threading.Thread(target=watch, name="tui-gym-parent-watch", daemon=True).start()


def end(process: Any, timeout: float = 5.0) -> None:
    """Kill a child and its process group (if still there) and reap it."""
    pid = process.pid
    if pid is not None and process.is_alive():
        with contextlib.suppress(OSError):
            os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(OSError):
            process.kill()
    process.join(timeout=timeout)


@contextlib.contextmanager
def stops_on_signals(stop: threading.Event) -> Iterator[None]:
    """While it runs on the main thread: SIGTERM and SIGHUP set `stop` (the caller ends
    its children and records what finished); elsewhere, nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    kinds = [getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)]
    previous = {kind: signal.getsignal(kind) for kind in kinds}

    def handler(signum: int, frame: Any) -> None:
        stop.set()

    for kind in kinds:
        signal.signal(kind, handler)
    try:
        yield
    finally:
        for kind, old in previous.items():
            signal.signal(kind, old)
