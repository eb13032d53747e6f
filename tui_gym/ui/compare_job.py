"""`CompareJob`: one comparison running on a worker thread, watched by the Compare view.

The view never waits on it: `run_compare` runs on the job's own thread,
its progress callbacks only keep the latest `CompareProgress`, and the
view's timer reads `progress`, `result` and `error` when it draws. `stop()`
sets the event `run_compare` watches, so what finished is still recorded;
`close()` stops and waits a bounded time for the thread (the app's exit
and a switch of game or view use it). A failure becomes one line in
`error`, never a traceback.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tui_gym.core.experiments import RunHistory, RunHistoryError

CLOSE_SECONDS = 5.0  # how long `close()` waits for the thread to end


class CompareJob:
    """A comparison on a thread: `start()`, then read `progress`, `result`, `error`."""

    def __init__(
        self,
        spec: Any,
        db: Path,
        run: Callable[..., Any] | None = None,
    ) -> None:
        """`run` is `run_compare` (or a function with its signature)."""
        if run is None:
            from tui_gym.core.experiments.compare import run_compare

            run = run_compare
        self.spec = spec
        self.db = db
        self._run = run
        self.stop_event = threading.Event()
        self.progress: Any = None  # the latest CompareProgress
        self.progress_count = 0  # how many progress reports came
        self.result: Any = None  # the CompareResult once it ends
        self.error: str | None = None
        self.started_at = 0.0
        self._thread = threading.Thread(target=self._work, name="compare", daemon=True)

    def start(self) -> None:
        self.started_at = time.monotonic()
        self._thread.start()

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    @property
    def done(self) -> bool:
        """Started and ended (with a result or an error)."""
        return self._thread.ident is not None and not self._thread.is_alive()

    @property
    def stopping(self) -> bool:
        return self.stop_event.is_set()

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

    def _report(self, progress: Any) -> None:
        self.progress = progress  # one assignment: the view reads whichever is latest
        self.progress_count += 1

    def _work(self) -> None:
        try:
            with RunHistory(self.db) as history:
                self.result = self._run(
                    self.spec, progress=self._report, stop=self.stop_event, history=history
                )
        except RunHistoryError as exc:
            self.error = f"Not recorded: {exc}"
        except ValueError as exc:  # settings a learner or the game refuses
            self.error = f"The comparison could not run: {exc}"
        except Exception as exc:  # shown as one line in the view, not raised into the app
            self.error = f"The comparison failed: {type(exc).__name__}: {exc}"


__all__ = ["CompareJob"]
