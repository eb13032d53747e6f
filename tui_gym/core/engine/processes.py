"""Child processes that never outlive the process that started them: a child calls
`watch_parent(pid)` first; the parent ends its children with `end(process)`."""

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

__all__ = ["context", "end", "handling", "stops_on_signals", "watch_parent"]

_PR_SET_PDEATHSIG = 1
WATCH_SECONDS = 0.2  # how often a child looks whether its parent is still there


def context() -> Any:
    """Fork on Linux (children inherit the compiled learners; they only run learners, so
    forking from the app's threads is safe), else spawn."""
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


def stops_on_signals(stop: threading.Event) -> contextlib.AbstractContextManager[None]:
    """While it runs on the main thread: SIGTERM and SIGHUP set `stop`."""
    return handling(("SIGTERM", "SIGHUP"), lambda signum, frame: stop.set())


@contextlib.contextmanager
def handling(names: tuple[str, ...], handler: Any, untouched: bool = False) -> Iterator[None]:
    """Signals `names` go to `handler` while the block runs on the main thread (with
    `untouched`, only those still on their default action)."""
    previous: dict[int, Any] = {}
    for name in names if threading.current_thread() is threading.main_thread() else ():
        sig = getattr(signal, name, None)
        if sig is None:
            continue
        try:
            old = signal.getsignal(sig)
            if untouched and old not in (signal.SIG_DFL, signal.default_int_handler):
                continue
            previous[sig] = old
            signal.signal(sig, handler)
        except (ValueError, OSError):
            continue
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
