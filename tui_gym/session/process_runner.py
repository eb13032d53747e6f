"""`ProcessRunner`: a `Runner` that trains in a child process (no shared interpreter lock).

While paused, the parent's `Session` is the truth. A request (start, one episode, one step)
hands the child the session's spec, hyperparameters, agent and progress; the child streams
snapshots back and a pause asks for the agent back. Every request has a number, and what
comes back lands in the agent it was made from: after a reset or a switch, a late handover
changes nothing shown. Sender and receiver threads talk to the child; `update()` takes in
what it said. A child that dies, or is silent for `HANG_SECONDS` while holding the agent, is
replaced, the agent kept as last handed over, and `error` says so.
"""

from __future__ import annotations

import collections
import contextlib
import multiprocessing as mp
import pickle
import queue
import signal
import threading
import time
import traceback
from dataclasses import dataclass
from multiprocessing import resource_tracker
from typing import TYPE_CHECKING, Any

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.engine.trainer import TrainerProgress
from tui_gym.session.runner import TrainingRunner
from tui_gym.session.speeds import DEFAULT_SPEED, Runner

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from tui_gym.session.session import Session

SNAPSHOT_INTERVAL = 0.05  # seconds between snapshots sent by the child
ALIVE_SECONDS = 0.1  # a child holding the agent speaks at least this often (while compiling)
ANIMATED_POLL = 0.01  # the child's look-out at animated speeds: every step is sent
REPLY_TIMEOUT = 10.0  # seconds `wait_idle()` waits by default for the agent to come back
HANG_SECONDS = 10.0  # silence while holding the agent after which the child is replaced
RESPAWN_LIMIT = 3  # deaths within RESPAWN_WINDOW after which no new child is started
RESPAWN_WINDOW = 60.0
EXIT_SECONDS = 1.0  # how long `close()` lets the child end by itself before killing it
SPAWN_DELAY = 1.0  # the first child waits this long (or for a request): the app draws first


@dataclass(frozen=True)
class SessionSpec:
    """What it takes to build the same session elsewhere."""

    env_id: str
    env_kwargs: dict[str, Any]
    choices: tuple[Any, ...]
    seed: int
    engine: str
    algorithm: str

    @classmethod
    def of(cls, session: Session) -> SessionSpec:
        return cls(session.env_id, dict(session.env_kwargs), tuple(session.choices),
                   session.seed, session.engine, session.algorithm)


@dataclass(frozen=True)
class Handover:
    """Everything that moves between the processes at a start or a pause."""

    spec: SessionSpec
    hp: Any  # the algorithm's Settings
    agent: Any  # the learner (any tui_gym.algorithms.Learner)
    progress: TrainerProgress

    @classmethod
    def of(cls, session: Session) -> Handover:
        return cls(SessionSpec.of(session), session.hp, session.agent, session.trainer.progress())


def _context() -> Any:
    """How children start: forked from a server that imported what every child needs, once,
    or spawned where there is no fork server."""
    if "forkserver" not in mp.get_all_start_methods():
        return mp.get_context("spawn")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["tui_gym.session.process_runner", "tui_gym.session.session",
                                "tui_gym.session.fork_server"])
    return ctx


_warming = threading.Lock()
_warmer: threading.Thread | None = None


def _server_ready(wake: threading.Event, wait: bool = False) -> bool:
    """Whether a child starts at once (with `wait`, once it does). The first call starts the
    server and waits for it in a thread (its first child does nothing), so no caller waits
    while it imports; `wake` is set when it is ready."""
    global _warmer
    with _warming:
        if _warmer is None:
            _warmer = threading.Thread(target=_warm, args=(wake,), name="tui-gym-warm",
                                       daemon=True)
            _warmer.start()
    if wait:
        _warmer.join()
    return not _warmer.is_alive()


def _warm(wake: threading.Event) -> None:
    ctx = _context()
    if ctx.get_start_method() == "forkserver":
        with contextlib.suppress(Exception):  # none: the first real child says why
            process = ctx.Process(target=int, daemon=True)
            process.start()
            process.join()
    wake.set()


@dataclass
class _Request:
    """A start or one-episode request whose agent the child holds."""

    number: int
    kind: str  # "start", "one" (an episode) or "step" (a transition)
    agent: Any  # the agent object the handover came from, and goes back to
    trainer: Any  # its trainer at the time
    latest: TrainingSnapshot | None = None
    pause_sent: bool = False


class _Child:
    """One training process, with a thread that sends to it and one that listens."""

    def __init__(self, inbox: collections.deque[tuple[_Child, tuple]],
                 wake: threading.Event) -> None:
        ctx = _context()
        self.conn, child_conn = ctx.Pipe()
        self.process = ctx.Process(
            target=child_main, args=(child_conn,), name="tui-gym-trainer", daemon=True
        )
        self.process.start()
        child_conn.close()
        self._inbox, self._wake = inbox, wake
        self._outbox: queue.SimpleQueue[bytes | None] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._reaping = threading.Lock()  # one join, or close, at a time (see `_join`)
        self.ready = False  # the child has said its first word
        self.awaited = 0  # requests sent and not yet answered
        self.last_heard = time.monotonic()
        self.hung = False
        self.ending = False
        threading.Thread(target=self._send_loop, name="tui-gym-sender", daemon=True).start()
        threading.Thread(target=self._receive_loop, name="tui-gym-receiver", daemon=True).start()

    def send(self, message: tuple, request: bool = False) -> None:
        """Queue a message, pickled now (it may change later)."""
        data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
        with self._lock:
            if request:
                self.awaited += 1
                self.last_heard = time.monotonic()
        self._outbox.put(data)

    def _send_loop(self) -> None:
        while True:
            data = self._outbox.get()
            if data is None:
                return
            try:
                self.conn.send_bytes(data)
            except (OSError, ValueError, TypeError):  # the child is gone: the receiver tells
                return

    def _receive_loop(self) -> None:
        conn = self.conn
        while True:
            try:
                if not conn.poll(0.25):
                    with self._lock:  # silent too long while it holds the agent?
                        since = time.monotonic() - self.last_heard
                        self.hung |= self.ready and self.awaited > 0 and since > HANG_SECONDS
                    if self.hung:
                        with contextlib.suppress(OSError):
                            self.process.kill()
                    continue
                message = conn.recv()
            # TypeError: the connection was closed (by `reap`) while this thread read it
            except (EOFError, OSError, ValueError, TypeError, pickle.UnpicklingError):
                break
            with self._lock:
                self.ready = True
                self.last_heard = time.monotonic()
                if message[0] == "returned":
                    self.awaited = max(0, self.awaited - 1)
            self._inbox.append((self, message))
            self._wake.set()
        self._join(5.0)  # reap it: no zombie left behind
        self._outbox.put(None)
        self._inbox.append((self, ("gone", self.process.exitcode)))
        self._wake.set()

    def end(self, wait: bool) -> None:
        """Ask the child to quit; with `wait`, make sure it has (killing it if need be)."""
        if not self.ending:
            self.ending = True
            with contextlib.suppress(Exception):
                self.send(("quit",))
            self._outbox.put(None)  # the sender stops
        if wait:
            self.reap()
        else:
            threading.Thread(target=self.reap, name="tui-gym-reaper", daemon=True).start()

    def reap(self) -> None:
        """Wait for the child to end, killing it when it does not by itself."""
        if self._join(EXIT_SECONDS):
            with contextlib.suppress(OSError):
                self.process.kill()
            self._join(EXIT_SECONDS)
        # One close at a time: two at once (a background reaper and the app's exit) would
        # both close the descriptor, the second whatever file has taken its number since.
        with self._reaping, contextlib.suppress(OSError):
            self.conn.close()

    def _join(self, timeout: float) -> bool:
        """Wait for the child to end; whether it is still alive. One thread at a time: a join
        racing another's reaping would take it for alive (and a kill could reach its pid's
        next owner)."""
        with self._reaping:
            self.process.join(timeout=timeout)
            return self.process.is_alive()


class ProcessRunner(Runner):
    """Trains a session in a child process, on request (see the module docstring)."""

    def __init__(self, session: Session, speed: int = DEFAULT_SPEED) -> None:
        self.session = session
        self.speed_index = speed
        self._error: BaseException | None = None
        self._finished = False
        self._want()  # run, one episode, steps asked for and not sent yet (a burst of `n`)
        self._pending: _Request | None = None
        self._numbers = 0
        self._last_sent_agent: Any = None  # to tell the child when the agent is a new one
        self._inbox: collections.deque[tuple[_Child, tuple]] = collections.deque()
        self._heard = threading.Event()
        self._deaths: collections.deque[float] = collections.deque()
        self._broken = ""  # why no new child is started (it kept dying), or empty
        self._closed = False
        self._ended: _Child | None = None  # the child `close()` ended
        # The first child starts once the app has drawn (or at the first request). The
        # resource tracker every child registers with starts now: under a running app the
        # standard error it hands on is Textual's capture, which has no file descriptor.
        resource_tracker.ensure_running()
        _server_ready(self._heard)
        self._child: _Child | None = None
        self._spawn_at = time.monotonic() + SPAWN_DELAY

    @property
    def error(self) -> BaseException | None:
        """Why training stopped, or what happened to the child (the owner clears it)."""
        self.update()
        return self._error

    @error.setter
    def error(self, value: BaseException | None) -> None:
        self._error = value

    @property
    def finished(self) -> bool:
        """The episode budget was reached."""
        self.update()
        return self._finished

    @finished.setter
    def finished(self, value: bool) -> None:
        self._finished = value

    @property
    def running(self) -> bool:
        """True while training is switched on (the child may still be getting the agent)."""
        self.update()
        return self._want_run

    @property
    def busy(self) -> bool:
        self.update()
        return self._wanted() or self._pending is not None

    def _wanted(self) -> bool:
        return self._want_run or self._want_one or self._want_step > 0

    def _want(self, run: bool = False, one: bool = False, step: int = 0) -> None:
        self._want_run, self._want_one, self._want_step = run, one, step

    @property
    def latest(self) -> TrainingSnapshot:
        """The child's latest snapshot while it trains the session's agent, else the session's."""
        self.update()
        request = self._pending
        if request is not None and request.latest is not None and self._current(request):
            return request.latest
        return self.session.trainer.latest

    @property
    def child_pid(self) -> int | None:
        """The training process's id (None when there is none)."""
        self._spawn(wait=True)
        child = self._child
        return None if child is None else child.process.pid

    def _current(self, request: _Request) -> bool:
        return request.agent is self.session.agent

    # --- controls ---------------------------------------------------------------
    def start(self) -> bool:
        return self._ask("start", False)

    def pause(self, wait: bool = True, timeout: float = REPLY_TIMEOUT) -> bool:
        self.update()  # the child hands the agent back in a moment, `update()` takes it in
        self._want()
        if self._pending is not None:
            self._ask_back(self._pending)
        return self.wait_idle(timeout) if wait else True

    def run_one_episode(self) -> bool:
        return self._ask("one", self._want_run or self._pending is not None)

    def run_one_step(self) -> bool:
        pending = self._pending
        return self._ask("step", self._want_run or self._want_one
                         or (pending is not None and pending.kind != "step"))

    def _ask(self, kind: str, busy: bool) -> bool:
        """Ask for a run ("start"), an episode ("one") or a step unless `busy`."""
        self.update()
        if self._broken:
            self._error = RuntimeError(self._broken)
            return kind != "start"
        if self.session.trainer.remaining == 0 and self._pending is None:
            self._finished = True
            return False
        if busy:
            return True
        self._error = None
        if kind == "start":
            self._finished = False
            self._want(run=True)
            request = self._pending
            if request is not None and request.kind in ("one", "step"):
                self._ask_back(request)  # then start from where the episode got to
        elif kind == "one":
            self._want_one = True
        else:
            self._want_step += 1
        self._sync()
        return True

    def set_hyperparameters(self, hp: Any) -> None:
        self.update()  # the child training the session's agent gets them too
        self.session.set_hyperparameters(hp)
        request = self._pending
        if request is not None and self._current(request) and self._child is not None:
            self._child.send(("hyperparameters", request.number, self.session.hp))

    def _speed_changed(self) -> None:
        if self._child is not None:
            self._child.send(("speed", self.speed_index))

    def wait_idle(self, timeout: float = REPLY_TIMEOUT) -> bool:
        deadline = time.monotonic() + timeout
        while True:
            self._heard.clear()
            self.update()
            if not (self._wanted() or self._pending is not None):
                return True
            left = deadline - time.monotonic()
            if left <= 0:
                return False
            self._heard.wait(min(left, 0.25))

    def close(self, wait: bool = True) -> None:
        self._closed = True
        self._want()
        child, self._child = self._child, None
        self._ended = child or self._ended
        if self._ended is not None:
            self._ended.end(wait)

    # --- taking in what the child says ------------------------------------------
    def update(self) -> None:
        """Take in what the child has said: snapshots, handed-back agents, its death."""
        inbox = self._inbox
        while inbox:
            child, message = inbox.popleft()
            if child is not self._child:
                continue  # a replaced child's last words
            kind, request = message[0], self._pending
            if kind == "gone":
                self._replace_child(child, message[1])
            elif kind not in ("snapshot", "returned") or request is None \
                    or message[1] != request.number:
                continue  # alive, or words on a request already answered
            elif kind == "snapshot":
                request.latest, scene, event = message[2:]
                if scene is not None:
                    self._shown = (request.agent, scene, event)
            else:
                self._take_back(request, *message[2:])
        self._sync()

    def _take_back(self, request: _Request, handover: Handover, reason: str,
                   error: str | None) -> None:
        self._pending = None
        current = self._current(request)
        try:
            request.agent.assign_from(handover.agent)
            trainer = request.trainer
            if current:
                # The session may have been rebuilt around the same agent meanwhile.
                trainer = self.session.trainer
                request.agent.set_hyperparameters(self.session.hp)
            trainer.restore(handover.progress)
        except Exception as exc:  # a handover that does not fit: keep what we have
            self._error = RuntimeError(f"the trained agent could not be taken back: {exc}")
            self._want_run = False
            return
        if not current:
            return  # a reset or a switch came first: it wins
        if reason == "finished":
            self._finished = True
            self._want_run = False
        elif reason == "error":
            self._error = RuntimeError(error or "training failed")
            self._want_run = False

    def _replace_child(self, child: _Child, exitcode: int | None) -> None:
        request, self._pending = self._pending, None
        was_training = self._wanted() or request is not None
        self._want()
        self._last_sent_agent = None
        self._child = None
        if self._closed:
            return
        now = time.monotonic()
        self._deaths.append(now)
        while self._deaths and now - self._deaths[0] > RESPAWN_WINDOW:
            self._deaths.popleft()
        if child.hung:
            how = f"stopped answering for {HANG_SECONDS:g} s and was ended"
        elif exitcode is not None and exitcode < 0:
            how = f"was killed (signal {-exitcode})"
        else:
            how = f"ended unexpectedly (exit code {exitcode})"
        episodes = self.session.trainer.episodes
        kept = (f"the agent is kept as last handed back ({episodes:,} episodes)"
                if was_training else "the agent is kept")
        if request is not None and request.latest is not None and self._current(request):
            lost = request.latest.episodes - episodes
            if lost > 0:
                kept += f"; the {lost:,} trained since are lost"
        if len(self._deaths) >= RESPAWN_LIMIT:
            self._broken = (
                f"the training process {how}, {len(self._deaths)} times within "
                f"{RESPAWN_WINDOW:g} s; {kept}, but training is off for this session "
                "(save the agent, or restart tui-gym with --runner thread)"
            )
            self._error = RuntimeError(self._broken)
            return
        if not self._start_child(f"the training process {how}, and a new one",
                                 f"{kept}, but training is off for this session"):
            return
        self._error = RuntimeError(f"the training process {how}; a new one is ready and {kept}")

    # --- sending ----------------------------------------------------------------
    def _ask_back(self, request: _Request) -> None:
        if not request.pause_sent and self._child is not None:
            request.pause_sent = True
            self._child.send(("pause", request.number))

    def _spawn(self, wait: bool = False) -> None:
        """The first child, once it is due (see `SPAWN_DELAY`) or asked for, and the server
        it starts from is ready (with `wait`, once it is)."""
        if self._child is None and self._ended is None and not (self._closed or self._broken) \
                and _server_ready(self._heard, wait):
            self._start_child("a training process", "training is off for this session")

    def _start_child(self, what: str, then: str) -> bool:
        """A new child; when none can start (no processes left, or the terminal and the
        process group gone as the app ends), training goes off with `error` saying so."""
        try:
            self._child = _Child(self._inbox, self._heard)
        except (OSError, ValueError) as exc:  # ValueError: the resource tracker's fds gone
            self._broken = f"{what} could not start ({exc}); {then}"
            self._error = RuntimeError(self._broken)
            return False
        return True

    def _sync(self) -> None:
        """Send the request the owner wants, once the child holds no agent."""
        if self._wanted() or time.monotonic() >= self._spawn_at:
            self._spawn()
        child = self._child
        if self._pending is not None or child is None or self._closed:
            return
        if self._want_run:
            kind = "start"
            if self.session.trainer.remaining == 0:
                self._finished = True
                self._want_run = False
                return
        elif self._want_one:
            kind = "one"
            self._want_one = False
        elif self._want_step:
            kind = "step"
            self._want_step -= 1
        else:
            return
        session = self.session
        self._numbers += 1
        request = _Request(self._numbers, kind, session.agent, session.trainer)
        fresh = session.agent is not self._last_sent_agent
        self._last_sent_agent = session.agent
        self._pending = request
        child.send((kind, request.number, Handover.of(session), self.speed_index, fresh),
                   request=True)


def child_main(conn: Connection) -> None:
    """The child process: a TrainingRunner on its own Session, driven through the pipe."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # ctrl+c is the app's to handle
    from tui_gym.session.session import Session

    conn.send(("ready",))
    session: Session | None = None
    spec: SessionSpec | None = None
    runner: TrainingRunner | None = None
    holding: int | None = None  # the number of the request whose agent the child holds
    holding_kind = ""
    last_sent = -1
    last_word = time.monotonic()

    def hand_back(reason: str, error: str | None = None) -> None:
        nonlocal holding
        assert session is not None and runner is not None
        runner.pause()
        number, holding = holding, None
        conn.send(("returned", number, Handover.of(session), reason, error))

    def take(message: tuple) -> None:
        nonlocal session, spec, runner, holding, holding_kind, last_sent
        kind, number, handover, speed, fresh = message
        try:
            if session is None or runner is None or fresh or handover.spec != spec:
                # A new game, new wrappers or a new agent: a fresh session, so that no
                # episode of the old one carries over.
                if runner is not None:
                    runner.close()
                spec = handover.spec
                session = Session(hp=handover.hp, **vars(spec))
                runner = TrainingRunner(session)
            session.hp = handover.hp
            session.agent.assign_from(handover.agent)
            session.agent.set_hyperparameters(handover.hp)
            session.trainer.restore(handover.progress)
        except Exception:  # nothing trained: the same agent goes back, with the reason
            conn.send(("returned", number, handover, "error", traceback.format_exc(limit=3)))
            return
        runner.set_speed(speed)
        holding, holding_kind, last_sent = number, kind, -1
        if kind == "one":
            runner.run_one_episode()
        elif kind == "step":
            runner.run_one_step()
        elif not runner.start():
            hand_back("finished")

    while True:
        try:
            animated = runner is not None and runner.speed.animated
            if conn.poll(ANIMATED_POLL if animated else SNAPSHOT_INTERVAL):
                message = conn.recv()
                kind = message[0]
                if kind == "quit":
                    break
                if kind in ("start", "one", "step"):
                    take(message)
                elif kind == "pause" and holding is not None and message[1] == holding:
                    hand_back("paused")
                elif kind == "speed" and runner is not None:
                    runner.set_speed(message[1])
                elif kind == "hyperparameters" and holding is not None and message[1] == holding:
                    assert runner is not None
                    runner.set_hyperparameters(message[2])
            if holding is None or runner is None or session is None:
                continue
            idle = not runner.busy  # read first: the snapshot below is then the last one
            snapshot = runner.latest
            if snapshot.version != last_sent:
                last_sent = snapshot.version
                conn.send(("snapshot", holding, snapshot, runner.last_scene, runner.last_event))
                last_word = time.monotonic()
            elif time.monotonic() - last_word > ALIVE_SECONDS:  # e.g. the engine compiling
                conn.send(("alive",))
                last_word = time.monotonic()
            if idle and runner.error is not None:
                hand_back("error", f"{runner.error}")
            elif idle:
                done = "finished" if runner.finished else "paused"
                hand_back({"one": "episode", "step": "step"}.get(holding_kind, done))
        except (EOFError, OSError):
            break
        except Exception:  # report, hand back what we have, and carry on
            detail = traceback.format_exc(limit=3)
            try:
                if holding is not None and session is not None and runner is not None:
                    hand_back("error", detail)
            except Exception:
                break
    if runner is not None:
        runner.close()
