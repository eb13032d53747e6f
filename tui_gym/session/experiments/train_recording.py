"""`TrainRecording`: one headless training run (`tui-gym train`) kept in the run history."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.experiments.paths import resolve_db_path
from tui_gym.core.experiments.records import RunKind, RunStatus
from tui_gym.session.experiments.app_recording import SessionRunLog
from tui_gym.session.experiments.live import ExactCheckpoints, run_results, run_spec

if TYPE_CHECKING:
    from tui_gym.session.evaluation import EvalReport
    from tui_gym.session.session import Session


class TrainRecording:
    """Records one training run into the history at `db` (None: the default one) on a writer
    thread of its own while the training goes on; with `enabled` False it records nothing."""

    def __init__(
        self, db: str | None = None, *, enabled: bool = True,
        warn: Callable[[str], None] = lambda line: None,
    ) -> None:
        self.path: Path | None = resolve_db_path(db) if enabled else None
        self.warn = warn
        self.run_id: int | None = None
        self._log = None if self.path is None else SessionRunLog(self.path)
        self._session: Session | None = None
        self._checkpoints: ExactCheckpoints | None = None
        self._after = 0

    def begin(self, session: Session) -> None:
        """Start recording: the run is written (status running) on the writer thread."""
        if self._log is None:
            return
        try:
            spec = run_spec(session, RunKind.TRAIN)
        except ValueError as exc:
            self._give_up(str(exc))
            return
        self._session = session
        self._after = session.trainer.episodes
        self._checkpoints = ExactCheckpoints(session)
        self._log.send(self, start=spec)
        self._checkpoints.take()

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
        """Write the curves, figures and saved agent's path with the final status, and wait
        for the writes to land; the run's id (None when it was not recorded)."""
        log, session, checkpoints = self._log, self._session, self._checkpoints
        if log is None or session is None or checkpoints is None:
            return None
        self._session = None
        snapshot = session.trainer.latest
        checkpoints.take(snapshot, final=True)
        curves, figures = run_results(snapshot, checkpoints, self._after, report)
        log.send(self, curves=curves, figures=figures, status=status,
                 agent_path=None if saved is None else Path(saved).resolve())
        log.close(wait=None)
        if log.problem is not None:
            self._give_up(log.problem)
            return None
        self.run_id = log.run_ids.get(self)
        return self.run_id

    def _give_up(self, problem: str) -> None:
        self.warn(f"this run is not recorded in the run history: {problem}")
        self.run_id = None
        self._session = None
        self._log = None

    def close(self) -> None:
        if self._log is not None:
            self._log.close(wait=None)

    def __enter__(self) -> TrainRecording:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        try:
            if exc_type is not None and self._session is not None:
                self.finish(status=RunStatus.ending(exc_type))
        finally:
            self.close()
