"""`TrainRecording`: one headless training run (`tui-gym train`) kept in the run history."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.paths import resolve_db_path
from tui_gym.core.experiments.records import RunKind, RunSpec, RunStatus
from tui_gym.session.experiments.live import ExactCheckpoints, run_results, run_spec

if TYPE_CHECKING:
    from tui_gym.session.evaluation import EvalReport
    from tui_gym.session.session import Session


class TrainRecording:
    """Records one training run into the history at `db` (None: `TUI_GYM_DB` or the data
    folder's); with `enabled` False it records nothing."""

    def __init__(
        self, db: str | None = None, *, enabled: bool = True,
        warn: Callable[[str], None] = lambda line: None,
    ) -> None:
        self.enabled = enabled
        self.path: Path | None = resolve_db_path(db) if enabled else None
        self.warn = warn
        self.run_id: int | None = None
        self._history: RunHistory | None = None
        self._session: Session | None = None
        self._checkpoints: ExactCheckpoints | None = None
        self._after = 0
        self._opening: threading.Thread | None = None
        self._problem: Exception | None = None  # why the file could not be opened

    def begin(self, session: Session) -> None:
        """Start recording: the file is opened and the run written (status running) on a
        thread of its own while the training goes on."""
        if not self.enabled or self.path is None:
            return
        try:
            spec = run_spec(session, RunKind.TRAIN)
        except ValueError as exc:
            self._give_up(exc)
            return
        self._session = session
        self._after = session.trainer.episodes
        self._checkpoints = ExactCheckpoints(session)
        self._opening = threading.Thread(target=self._open, args=(spec,), name="run-history",
                                         daemon=True)
        self._opening.start()
        self._checkpoints.take()

    def _open(self, spec: RunSpec) -> None:
        try:
            self._history = RunHistory(self.path)  # type: ignore[arg-type]
            self.run_id = self._history.start_run(spec)
        except (RunHistoryError, ValueError, OSError) as exc:
            self._problem = exc

    def _opened(self) -> bool:
        """Wait for the file to be open and the run written; False (and one warning) if not."""
        if self._opening is not None:
            self._opening.join()
            self._opening = None
            if self._problem is not None:
                self._give_up(self._problem)
        return self._history is not None and self.run_id is not None

    def on_chunk(self, snapshot: TrainingSnapshot) -> None:
        """`Session.train`'s callback: an exact-value checkpoint when they are cheap."""
        if self._checkpoints is not None:
            self._checkpoints.take(snapshot)

    def chain(
        self, callback: Callable[[TrainingSnapshot], None]
    ) -> Callable[[TrainingSnapshot], None]:
        """`callback` (say, a progress bar's), then `on_chunk`."""

        def both(snapshot: TrainingSnapshot) -> None:
            callback(snapshot)
            self.on_chunk(snapshot)

        return both

    def finish(
        self, report: EvalReport | None = None, saved: str | Path | None = None,
        status: RunStatus = RunStatus.FINISHED,
    ) -> int | None:
        """Write the curves, figures and saved agent's path with the final status; the
        run's id (None when it was not recorded)."""
        if not self._opened():
            return None
        history, session, checkpoints = self._history, self._session, self._checkpoints
        if history is None or session is None or checkpoints is None or self.run_id is None:
            return None
        snapshot = session.trainer.latest
        checkpoints.take(snapshot, final=True)
        curves, figures = run_results(snapshot, checkpoints, self._after, report)
        try:
            history.update(self.run_id, curves=curves, figures=figures, status=status,
                           agent_path=None if saved is None else Path(saved).resolve())
        except (RunHistoryError, ValueError) as exc:
            self._give_up(exc)
            return None
        finally:
            self._session = None
        return self.run_id

    def _give_up(self, exc: Exception) -> None:
        self.warn(f"this run is not recorded in the run history: {exc}")
        self.run_id = None
        self._session = None
        if self._history is not None:
            self._history.close()
            self._history = None

    def close(self) -> None:
        if self._opening is not None:
            self._opening.join()
            self._opening = None
        if self._history is not None:
            self._history.close()
            self._history = None

    def __enter__(self) -> TrainRecording:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        try:
            if exc_type is not None and self._session is not None:
                interrupted = issubclass(exc_type, KeyboardInterrupt)
                self.finish(status=RunStatus.INTERRUPTED if interrupted else RunStatus.FAILED)
        finally:
            self.close()
