"""`SessionRunLog`: every run trained in the app, kept in the run history by a writer
thread (which a `train` run's recording uses too)."""

from __future__ import annotations

import queue
import sqlite3
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.records import RunKind, RunSpec, RunStatus
from tui_gym.session.experiments.live import ExactCheckpoints, run_results, run_spec

if TYPE_CHECKING:
    from tui_gym.session.session import Session

FLUSH_SECONDS = 2.0  # how often an open run's curves are written
CLOSE_WAIT_SECONDS = 3.0  # how long `close()` waits for the last writes


@dataclass
class _OpenRun:
    agent: Any  # the learner this run trains
    after: int  # the agent's episodes before the run began
    checkpoints: ExactCheckpoints
    spec: RunSpec  # the settings it trains with, as of the last look
    settings: tuple[Any, ...]  # what `spec` was made from (see `_settings`)
    token: object = field(default_factory=object)  # names the run to the writer
    episodes: int = 0  # the latest snapshot's
    flushed: int = -1  # episodes at the last flush


def _settings(session: Session) -> tuple[Any, ...]:
    # The session replaces these objects when a setting changes: comparing them is cheap.
    return (id(session.hp), id(session.env_kwargs), session.choices, session.algorithm)


class SessionRunLog:
    """Records the app's runs into the history at `path` (see the module)."""

    def __init__(
        self, path: str | Path, *, flush_seconds: float = FLUSH_SECONDS,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.path = Path(path)
        self.flush_seconds = flush_seconds
        self.clock = clock
        self._run: _OpenRun | None = None
        self._agent: Any = None  # the agent seen last, and its episodes then
        self._baseline = 0
        self._next_flush = 0.0
        self._jobs: queue.SimpleQueue[tuple[Any, ...] | None] = queue.SimpleQueue()
        self._writer: threading.Thread | None = None
        self.problem: str | None = None  # why writing failed (set by the writer thread)
        self._told = False
        self._last_snapshot: TrainingSnapshot | None = None  # the open run's latest
        self.run_ids: dict[object, int] = {}  # token -> id, once the writer has it

    def observe(self, session: Session, snapshot: TrainingSnapshot) -> str | None:
        """Follow the session's training; a line to show when the history failed (once)."""
        if self.problem is not None:
            if self._told:
                return None
            self._told = True
            self._run = None
            return f"Runs are not recorded in the run history: {self.problem}"
        agent = session.agent
        run = self._run
        if run is not None and (run.agent is not agent or snapshot.episodes < run.episodes):
            self._end(run)
            run = None
        if agent is not self._agent:
            self._agent, self._baseline = agent, snapshot.episodes
        if run is None:
            if snapshot.episodes <= self._baseline:
                return None
            run = self._begin(session, snapshot)
        settings = _settings(session)
        if settings != run.settings:  # edited mid-run: the run records what it trains with
            run.spec, run.settings, run.flushed = run_spec(session, RunKind.APP), settings, -1
        run.episodes = snapshot.episodes
        now = self.clock()
        if now >= self._next_flush and run.episodes != run.flushed:
            self._next_flush = now + self.flush_seconds
            run.checkpoints.take(snapshot)
            curves, figures = run_results(snapshot, run.checkpoints, run.after)
            self.send(run.token, curves=curves, figures=figures, spec=run.spec)
            run.flushed = run.episodes
        self._last_snapshot = snapshot
        return None

    def saved(self, session: Session, path: str | Path) -> None:
        """The session's agent was saved to `path`: its run records where."""
        run = self._run
        if run is not None and run.agent is session.agent and self.problem is None:
            self.send(run.token, agent_path=str(Path(path).resolve()))

    def _begin(self, session: Session, snapshot: TrainingSnapshot) -> _OpenRun:
        spec = run_spec(session, RunKind.APP)
        run = _OpenRun(agent=session.agent, after=self._baseline,
                       checkpoints=ExactCheckpoints(session), spec=spec,
                       settings=_settings(session))
        self._run = run
        self._next_flush = self.clock() + self.flush_seconds
        self.send(run.token, start=spec)
        run.checkpoints.take(snapshot)  # the exact value near the run's start
        return run

    def _end(self, run: _OpenRun) -> None:
        # No checkpoint here: the session may have been rebuilt around another table.
        curves, figures = run_results(self._last_snapshot, run.checkpoints, run.after)
        self.send(run.token, curves=curves, figures=figures, spec=run.spec,
                  status=RunStatus.FINISHED)
        self._run = None
        self._baseline = run.episodes

    def close(self, wait: float | None = CLOSE_WAIT_SECONDS) -> None:
        """End the open run and wait up to `wait` seconds (None: no limit) for every write."""
        if self._run is not None and self.problem is None:
            self._end(self._run)
        writer = self._writer
        if writer is not None:
            self._jobs.put(None)
            writer.join(wait)
            self._writer = None

    def send(self, token: object, start: RunSpec | None = None, **changes: Any) -> None:
        """On the writer thread, in order: start a run of `start` named `token`, or make
        `changes` to that run (`RunHistory.update`'s arguments)."""
        if self._writer is None:
            self._writer = threading.Thread(target=self._write_all, name="run-history", daemon=True)
            self._writer.start()
        self._jobs.put((token, start, changes))

    def _write_all(self) -> None:
        history: RunHistory | None = None
        try:
            while (job := self._jobs.get()) is not None:
                token, start, changes = job
                if self.problem is not None:
                    continue
                try:
                    if history is None:
                        history = RunHistory(self.path)
                    if start is not None:
                        self.run_ids[token] = history.start_run(start)
                    elif token in self.run_ids:
                        history.update(self.run_ids[token], **changes)
                except (RunHistoryError, ValueError, OSError, sqlite3.Error) as exc:
                    self.problem = str(exc)
        finally:
            if history is not None:
                history.close()
