"""`CompareJob`: one comparison running on a worker thread, watched by the Compare view."""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tui_gym.core.experiments import RunHistory, RunHistoryError
from tui_gym.ui.widgets.numbers import cut

if TYPE_CHECKING:
    from tui_gym.session.experiments.compare import (
        AlgorithmOutcome,
        CompareProgress,
        CompareResult,
        CompareSpec,
    )

CLOSE_SECONDS = 5.0  # how long `close()` waits for the thread to end
OUTCOMES_SECONDS = 0.4  # the live outcomes are aggregated at most this often
OUTCOMES_SHARE = 10  # and after this many times as long as aggregating them last took
NICENESS = 10  # the comparison's thread and processes yield the cores to the app's


class CompareJob:
    """A comparison on a thread: `start()`, then read `progress`, `result`, `error`."""

    def __init__(
        self, spec: CompareSpec, db: Path, run: Callable[..., Any] | None = None,
        processes: int | None = None, resume: int | None = None,
    ) -> None:
        """`run` is `run_compare` (or a function with its signature); `processes` and
        `resume` are its own."""
        if run is None:
            from tui_gym.session.experiments.compare import run_compare

            run = run_compare
        self.spec = spec
        self.db = db
        self._run = run
        self.processes = processes
        self.resume = resume
        self.stop_event = threading.Event()
        self.progress: CompareProgress | None = None  # the latest report
        self.outcomes: tuple[AlgorithmOutcome, ...] = ()  # the latest ones aggregated
        self._aggregated = (float("-inf"), 0.0)  # when they were, and what it took
        self.progress_count = 0  # how many reports came
        self.result: CompareResult | None = None  # once it ends
        self.error: str | None = None
        self.started_at = 0.0
        self._thread = threading.Thread(target=self._work, name="compare", daemon=True)

    def start(self) -> None:
        """Start the thread; call it from the app's thread (see `_start_resource_tracker`)."""
        if self.processes != 0:
            _start_resource_tracker()
        self.started_at = time.monotonic()
        self._thread.start()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    @property
    def done(self) -> bool:
        """Started and ended (with a result or an error)."""
        return self._thread.ident is not None and not self._thread.is_alive()

    def stop(self) -> None:
        """Ask the comparison to end; what finished is kept and recorded."""
        self.stop_event.set()

    def close(self, timeout: float = CLOSE_SECONDS) -> bool:
        """Stop and wait up to `timeout` seconds for the thread; whether it ended."""
        self.stop()
        if self._thread.ident is None:
            return True
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _report(self, progress: CompareProgress) -> None:
        """Keep the latest report; aggregate its outcomes here, on the comparison's thread,
        when due (a run of many seeds would spend its time aggregating each task's)."""
        start = time.monotonic()
        at, cost = self._aggregated
        if progress.done >= progress.total or start - at >= max(OUTCOMES_SECONDS,
                                                                OUTCOMES_SHARE * cost):
            self.outcomes = progress.outcomes
            self._aggregated = (start, time.monotonic() - start)
        self.progress = progress  # one assignment: the view reads whichever is latest
        self.progress_count += 1

    def _work(self) -> None:
        from tui_gym.session.experiments.compare import RESUME_ADVICE, ResumeError

        # This thread's priority, and so that of the processes it starts (Linux only:
        # elsewhere `os.nice` would lower the whole app).
        if sys.platform.startswith("linux"):
            with contextlib.suppress(OSError):
                os.nice(NICENESS)
        try:
            with RunHistory(self.db) as history:
                self.result = self._run(
                    self.spec, progress=self._report, stop=self.stop_event, history=history,
                    processes=self.processes, resume=self.resume,
                )
        except ResumeError as exc:  # other settings: one line, without the command's advice
            self.error = f"Not resumed: {_one_line(exc).removesuffix(RESUME_ADVICE)}"
        except RunHistoryError as exc:
            self.error = f"Not recorded: {_one_line(exc)}"
        except ValueError as exc:  # settings a learner or the game refuses
            self.error = f"The comparison could not run: {_one_line(exc)}"
        except Exception as exc:  # shown as one line in the view, not raised into the app
            self.error = f"The comparison failed: {type(exc).__name__}: {_one_line(exc)}"


def _one_line(exc: BaseException, limit: int = 300) -> str:
    return cut(" ".join(str(exc).split()), limit)


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker now, with the real stderr in place (inside
    the app `sys.stderr` has file number -1: "bad value(s) in fds_to_keep")."""
    from multiprocessing import resource_tracker

    captured = sys.stderr
    if sys.__stderr__ is None:
        return
    sys.stderr = sys.__stderr__
    try:
        resource_tracker.ensure_running()
    except OSError:
        pass  # then the comparison says why it cannot start its processes
    finally:
        sys.stderr = captured


__all__ = ["CompareJob"]
