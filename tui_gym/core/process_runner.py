"""Training in a child process: the UI's Python never shares a core with the trainer.

`ProcessRunner` has the same surface as `TrainingRunner` (start, pause,
toggle, run_one_episode, speeds, latest, last_scene, error, finished), but
the training runs in a separate process, so the trainer and the event loop
never compete for one interpreter lock.

Ownership is simple: while paused, the parent's `Session` is the truth; on
`start()` the parent sends the session's spec (game, wrappers, seed,
hyperparameters), its agent and its trainer's progress to the child; while
running, the child streams snapshots back (about 20 a second); on `pause()`
the child sends the agent and progress back and the parent's session takes
them over, so saving, evaluating or watching the agent see every episode.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import threading
import time
import traceback
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from tui_gym.core.runner import DEFAULT_SPEED, SPEEDS, Speed, TrainingRunner
from tui_gym.core.training import StepEvent, TrainerProgress, TrainingSnapshot

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from tui_gym.core.session import Session

SNAPSHOT_INTERVAL = 0.05  # seconds between snapshots sent by the child
REPLY_TIMEOUT = 10.0  # seconds to wait for the child to hand the agent back


@dataclass(frozen=True)
class SessionSpec:
    """What it takes to build the same session elsewhere."""

    env_id: str
    env_kwargs: dict[str, Any]
    choices: tuple[Any, ...]
    seed: int
    engine: str

    @classmethod
    def of(cls, session: Session) -> SessionSpec:
        return cls(
            session.env_id,
            dict(session.env_kwargs),
            tuple(session.choices),
            session.seed,
            getattr(session, "engine", "auto"),
        )


@dataclass(frozen=True)
class Handover:
    """Everything that moves between the processes at a start or a pause."""

    spec: SessionSpec
    hp: Any  # Hyperparameters
    agent: Any  # QAgent
    progress: TrainerProgress


def _handover(session: Session) -> Handover:
    return Handover(SessionSpec.of(session), session.hp, session.agent,
                    session.trainer.progress())


def _take_over(session: Session, handover: Handover) -> None:
    """Adopt the child's agent and progress, keeping the parent's objects."""
    session.agent.assign_from(handover.agent)
    session.trainer.restore(handover.progress)


class ProcessRunner:
    """Trains a session in a child process, on request (see the module docstring)."""

    def __init__(self, session: Session, speed: int = DEFAULT_SPEED) -> None:
        self.session = session
        self.speed_index = speed
        self.last_event: StepEvent | None = None
        self.last_scene: dict | None = None
        self.error: BaseException | None = None
        self.finished = False
        self._latest: TrainingSnapshot | None = None
        self._running = False
        self._busy = threading.Event()  # set while the child holds the agent
        self._returned = threading.Event()
        self._returned.set()
        self._send_lock = threading.Lock()
        ctx = mp.get_context("spawn")
        self._conn, child_conn = ctx.Pipe()
        self._process = ctx.Process(
            target=child_main, args=(child_conn,), name="tui-gym-trainer", daemon=True
        )
        self._process.start()
        child_conn.close()
        self._closed = False
        self._receiver = threading.Thread(target=self._receive, name="tui-gym-receiver",
                                          daemon=True)
        self._receiver.start()

    # --- controls ------------------------------------------------------------
    @property
    def speed(self) -> Speed:
        return SPEEDS[self.speed_index]

    @property
    def running(self) -> bool:
        return self._running

    @property
    def latest(self) -> TrainingSnapshot:
        if self._running and self._latest is not None:
            return self._latest
        return self.session.trainer.latest

    def _send(self, message: tuple) -> None:
        with self._send_lock:
            self._conn.send(message)

    def start(self) -> bool:
        if self.session.trainer.remaining == 0:
            self.finished = True
            return False
        if self._running:
            return True
        self.wait_idle()
        self.finished = False
        self.error = None
        self._latest = None
        self._returned.clear()
        self._running = True
        self._send(("start", _handover(self.session), self.speed_index))
        return True

    def pause(self, wait: bool = True, timeout: float = REPLY_TIMEOUT) -> None:
        if self._running:
            self._send(("pause",))
        if wait:
            self.wait_idle(timeout)

    def toggle(self) -> bool:
        if self._running:
            self.pause(wait=False)
            return False
        return self.start()

    def run_one_episode(self) -> None:
        if self._running or not self._returned.is_set():
            return
        self.error = None
        self._returned.clear()
        self._send(("one", _handover(self.session), self.speed_index))

    def set_speed(self, index: int) -> Speed:
        self.speed_index = max(0, min(len(SPEEDS) - 1, index))
        self._send(("speed", self.speed_index))
        return self.speed

    def faster(self) -> Speed:
        return self.set_speed(self.speed_index + 1)

    def slower(self) -> Speed:
        return self.set_speed(self.speed_index - 1)

    def wait_idle(self, timeout: float = REPLY_TIMEOUT) -> bool:
        """Wait until the child has handed the agent back (if it has it)."""
        return self._returned.wait(timeout)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(OSError, ValueError):
            self._send(("quit",))
        self._process.join(timeout=3.0)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(timeout=2.0)
        self._conn.close()

    # --- what the child says -------------------------------------------------
    def _receive(self) -> None:
        while True:
            try:
                message = self._conn.recv()
            except (EOFError, OSError):
                if not self._closed:
                    self.error = RuntimeError("the training process ended unexpectedly")
                self._running = False
                self._returned.set()
                return
            kind = message[0]
            if kind == "snapshot":
                _, snapshot, scene, event = message
                self._latest = snapshot
                self.last_scene = scene
                self.last_event = event
            elif kind == "returned":
                _, handover, finished, error = message
                _take_over(self.session, handover)
                self.finished = finished
                if error:
                    self.error = RuntimeError(error)
                self._running = False
                self._latest = None
                self._returned.set()


def child_main(conn: Connection) -> None:
    """The child process: a TrainingRunner on its own Session, driven through the pipe."""
    from tui_gym.core.session import Session

    session: Session | None = None
    spec: SessionSpec | None = None
    runner: TrainingRunner | None = None
    holding = False  # the child has the agent (between start/one and its return)
    one_episode_target: int | None = None
    last_sent = -1

    def hand_back(error: str | None = None) -> None:
        nonlocal holding, one_episode_target
        assert session is not None and runner is not None
        runner.pause()
        conn.send(("returned", _handover(session), runner.finished, error))
        holding = False
        one_episode_target = None

    while True:
        try:
            ready = conn.poll(SNAPSHOT_INTERVAL)
            if ready:
                message = conn.recv()
                kind = message[0]
                if kind == "quit":
                    break
                if kind in ("start", "one"):
                    _, handover, speed = message
                    if spec != handover.spec or session is None:
                        if runner is not None:
                            runner.close()
                        s = handover.spec
                        session = Session(env_id=s.env_id, env_kwargs=s.env_kwargs,
                                          choices=s.choices, hp=handover.hp, seed=s.seed,
                                          engine=s.engine)
                        spec = handover.spec
                        runner = TrainingRunner(session)
                    session.set_hyperparameters(handover.hp)
                    session.agent.assign_from(handover.agent)
                    session.agent.set_hyperparameters(handover.hp)
                    session.trainer.restore(handover.progress)
                    runner.set_speed(speed)
                    holding = True
                    if kind == "start":
                        runner.start()
                    else:
                        one_episode_target = session.trainer.episodes + 1
                        runner.run_one_episode()
                elif kind == "pause" and holding:
                    hand_back()
                elif kind == "speed" and runner is not None:
                    runner.set_speed(message[1])
            if runner is None or session is None:
                continue
            snapshot = runner.latest
            if holding and snapshot.version != last_sent:
                last_sent = snapshot.version
                conn.send(("snapshot", snapshot, runner.last_scene, runner.last_event))
            if holding and one_episode_target is not None:
                if session.trainer.episodes >= one_episode_target and runner.wait_idle(0.0):
                    hand_back()
            elif holding and not runner.running:
                error = runner.error
                hand_back(None if error is None else f"{error}")
        except (EOFError, OSError, BrokenPipeError):
            break
        except Exception:  # report, hand back what we have, and carry on
            detail = traceback.format_exc(limit=3)
            try:
                if holding and session is not None and runner is not None:
                    hand_back(detail)
            except Exception:
                break
    if runner is not None:
        runner.close()
    time.sleep(0)
