"""`SessionRunLog`: every run trained in the app, kept in the run history."""

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
        self._problem: str | None = None  # set by the writer thread
        self._told = False
        self._last_snapshot: TrainingSnapshot | None = None  # the open run's latest
        self.run_ids: dict[object, int] = {}  # token -> id, once the writer has it

    # --- on the app's timer ----------------------------------------------------
    def observe(self, session: Session, snapshot: TrainingSnapshot) -> str | None:
        """Follow the session's training; a line to show when the history failed (once)."""
        if self._problem is not None:
            if self._told:
                return None
            self._told = True
            self._run = None
            return self._problem
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
            self._send("update", run, *run_results(snapshot, run.checkpoints, run.after), run.spec)
            run.flushed = run.episodes
        self._last_snapshot = snapshot
        return None

    def saved(self, session: Session, path: str | Path) -> None:
        """The session's agent was saved to `path`: its run records where."""
        run = self._run
        if run is not None and run.agent is session.agent and self._problem is None:
            self._send("agent", run, str(Path(path).resolve()))

    def _begin(self, session: Session, snapshot: TrainingSnapshot) -> _OpenRun:
        spec = run_spec(session, RunKind.APP)
        run = _OpenRun(agent=session.agent, after=self._baseline,
                       checkpoints=ExactCheckpoints(session), spec=spec,
                       settings=_settings(session))
        self._run = run
        self._next_flush = self.clock() + self.flush_seconds
        self._send("start", run, spec)
        run.checkpoints.take(snapshot)  # the exact value near the run's start
        return run

    def _end(self, run: _OpenRun) -> None:
        # No checkpoint here: the session may have been rebuilt around another table.
        curves, figures = run_results(self._last_snapshot, run.checkpoints, run.after)
        self._send("finish", run, curves, figures, run.spec)
        self._run = None
        self._baseline = run.episodes

    def close(self) -> None:
        """End the open run and wait (briefly) for every write to land."""
        if self._run is not None and self._problem is None:
            self._end(self._run)
        writer = self._writer
        if writer is not None:
            self._jobs.put(None)
            writer.join(CLOSE_WAIT_SECONDS)
            self._writer = None

    # --- the writer thread ---------------------------------------------------
    def _send(self, kind: str, run: _OpenRun, *payload: Any) -> None:
        if self._writer is None:
            self._writer = threading.Thread(target=self._write_all, name="run-history", daemon=True)
            self._writer.start()
        self._jobs.put((kind, run.token, *payload))

    def _write_all(self) -> None:
        history: RunHistory | None = None
        try:
            while (job := self._jobs.get()) is not None:
                if self._problem is not None:
                    continue
                try:
                    if history is None:
                        history = RunHistory(self.path)
                    self._write(history, job)
                except (RunHistoryError, ValueError, OSError, sqlite3.Error) as exc:
                    self._problem = f"Runs are not recorded in the run history: {exc}"
        finally:
            if history is not None:
                history.close()

    def _write(self, history: RunHistory, job: tuple[Any, ...]) -> None:
        kind, token, *payload = job
        if kind == "start":
            spec: RunSpec = payload[0]
            self.run_ids[token] = history.start_run(spec)
            return
        run_id = self.run_ids.get(token)
        if run_id is None:
            return
        if kind == "agent":
            history.update(run_id, agent_path=payload[0])
            return
        curves, figures, spec = payload
        status = RunStatus.FINISHED if kind == "finish" else None
        history.update(run_id, curves=curves, figures=figures, status=status, spec=spec)
