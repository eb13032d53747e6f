"""The players a benchmark runs: built-in ones in this process, or a program."""

from __future__ import annotations

import contextlib
import json
import os
import queue
import select
import shlex
import subprocess
import threading
import time
from abc import ABC, abstractmethod
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from tui_gym.benchmark.group import start_group
from tui_gym.benchmark.referee import Referee
from tui_gym.session.protocol import parse_request, read_batches

MAX_STRIKES = 3  # decisions in a row not made in time before a player counts as gone
STARTUP_S = 10.0  # a program's first request may take this long (its start-up)
EXIT_GRACE_S = 2.0  # after the last episode, time for a program to exit on end of input
STDERR_LINES = 5  # lines of a program's stderr kept for the summary


class PlayerError(ValueError):
    """A player that cannot be set up (no such program, an unreadable agent file)."""


@dataclass
class PlayOutcome:
    """How a player played: each decision's time, and how it ended, in words."""

    decision_times: list[float] = field(default_factory=list)
    status: str = "played every episode"
    exit_code: int | None = None
    stderr_tail: str = ""


class Player(ABC):
    """One player of a benchmark; `label` names it in results and the leaderboard."""

    label: str

    @abstractmethod
    def play(self, referee: Referee, decision_timeout: float) -> PlayOutcome:
        """Play every episode of `referee`'s benchmark."""


class InProcessPlayer(Player):
    """A player in this process: `choose` picks an action name in the current state."""

    @abstractmethod
    def choose(self, referee: Referee) -> str: ...

    def play(self, referee: Referee, decision_timeout: float) -> PlayOutcome:
        outcome = PlayOutcome()
        while not referee.finished:
            if referee.seat.done:  # the next episode is due
                referee.handle({"cmd": "reset"})
                continue
            started = time.perf_counter()
            action = self.choose(referee)
            spent = time.perf_counter() - started
            outcome.decision_times.append(spent)
            if spent > decision_timeout:
                referee.timeout()
            else:
                referee.handle({"cmd": "step", "action": action})
        return outcome


class RandomPlayer(InProcessPlayer):
    """A uniformly random legal action (seeded)."""

    label = "random"

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def choose(self, referee: Referee) -> str:
        legal = referee.seat.legal_actions()
        return legal[int(self.rng.integers(len(legal)))]


class OptimalPlayer(InProcessPlayer):
    """An optimal action from the exact hint (the unwrapped game's where the wrappers
    change it beyond the exact figures; the default where the hint names none)."""

    label = "optimal"

    def choose(self, referee: Referee) -> str:
        hint = referee.seat.hint()
        best = hint.get("optimal_actions") or hint.get("unwrapped_optimal_actions")
        return str(best[0]) if best else referee.default_action()


class AgentPlayer(InProcessPlayer):
    """A saved agent's greedy action (ties and unlearned states at random, seeded)."""

    def __init__(self, path: str, seed: int) -> None:
        from tui_gym.session.session import Session
        from tui_gym.session.storage import StorageError

        try:
            self.session = Session.load(path)
        except (StorageError, OSError, ValueError) as exc:
            raise PlayerError(str(exc)) from None
        self.label = f"agent {Path(path).name}"
        self.rng = np.random.default_rng(seed)

    def check_game(self, env_id: str) -> None:
        """PlayerError unless the agent plays `env_id`."""
        if self.session.env_id != env_id:
            raise PlayerError(f"the agent plays {self.session.game.title} "
                              f"({self.session.env_id}), not {env_id}")

    def choose(self, referee: Referee) -> str:
        names = referee.entry.actions
        last = referee.seat.handler.game.last
        assert last is not None  # a decision is asked for in a running episode
        greedy = self.session.greedy_actions_for(last.observation)
        options = greedy[0] if greedy else tuple(range(len(names)))
        return names[options[int(self.rng.integers(len(options)))]]


_EOF = object()
_TOO_LONG = object()
_TIMEOUT = object()


class _Program:
    """A running program's pipes: its output read on a thread, a bounded tail of its
    stderr, and writes to its input that give up when it stops reading."""

    def __init__(self, argv: list[str]) -> None:
        try:
            self.group = start_group(
                argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE
            )
        except OSError as exc:
            raise PlayerError(f"cannot start {argv[0]!r}: {exc.strerror or exc}") from None
        self.process = self.group.process
        assert self.process.stdin and self.process.stdout and self.process.stderr
        self.lines: queue.Queue[tuple[float, Any]] = queue.Queue()  # (when read, line)
        self.stderr: deque[str] = deque(maxlen=STDERR_LINES)
        self._in = self.process.stdin.fileno()
        os.set_blocking(self._in, False)
        threading.Thread(target=self._read, args=(self.process.stdout,), daemon=True).start()
        self._stderr_done = threading.Thread(
            target=self._drain, args=(self.process.stderr,), daemon=True
        )
        self._stderr_done.start()

    def _read(self, stream: IO[bytes]) -> None:
        with contextlib.suppress(OSError, ValueError):
            for batch in read_batches(stream):
                # Stamped here, as read: the main thread may be slow to take it.
                for line in batch:
                    self.lines.put((time.monotonic(), _TOO_LONG if line is None else line))
        self.lines.put((time.monotonic(), _EOF))

    def _drain(self, stream: IO[bytes]) -> None:
        with contextlib.suppress(OSError, ValueError):
            for batch in read_batches(stream, limit=4096):
                self.stderr.extend(line.decode("utf-8", "replace").rstrip()[:200]
                                   for line in batch if line is not None and line.strip())

    def next_line(self, timeout: float) -> tuple[float, Any]:
        """When it was read, and the next line it wrote (or `_EOF`, `_TOO_LONG`);
        `_TIMEOUT` after `timeout` s without one."""
        try:
            return self.lines.get(timeout=timeout) if timeout > 0 else self.lines.get_nowait()
        except queue.Empty:
            return time.monotonic(), _TIMEOUT

    def send(self, data: bytes, timeout: float) -> bool:
        """Write `data` to its input; False if it stops reading (for `timeout` s) or is gone."""
        deadline = time.monotonic() + timeout
        view = memoryview(data)
        while view:
            try:
                written = os.write(self._in, view)
            except BlockingIOError:
                written = 0
            except OSError:  # a broken pipe: it closed its input or exited
                return False
            view = view[written:]
            if view:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                select.select([], [self._in], [], left)
        return True

    def stop(self, grace: float) -> int | None:
        """Close its input, give it `grace` s to exit, then end its whole process group;
        its exit code (None when it had to be ended)."""
        code = self.group.end(grace)
        self._stderr_done.join(timeout=1.0)
        return code


class ProcessPlayer(Player):
    """A program speaking the JSON-lines protocol on its stdout (requests) and stdin."""

    def __init__(self, command: str) -> None:
        try:
            self.argv = shlex.split(command)
        except ValueError as exc:
            raise PlayerError(f"cannot read the command {command!r}: {exc}") from None
        if not self.argv:
            raise PlayerError("the player's command is empty")
        # Named by its words without their folders: "python heuristic_player.py".
        self.label = " ".join(Path(word).name if "/" in word else word for word in self.argv)

    def play(self, referee: Referee, decision_timeout: float) -> PlayOutcome:
        program = _Program(self.argv)
        outcome = PlayOutcome()
        gone = ""
        played = False
        try:
            gone = self._serve(program, referee, decision_timeout, outcome)
            if gone:
                outcome.status = f"{gone} in episode {referee.started} of {referee.episodes}; " \
                                 "the rest was played with the default action"
                while not referee.finished:
                    referee.play_default()
            played = True
        finally:
            # A program done for but still running, or a benchmark cut short (ctrl+c, a
            # signal, an error), ends it at once; others may exit on their own once their
            # input ends.
            running = program.process.poll() is None
            code = program.stop(EXIT_GRACE_S if played and not (gone and running) else 0.0)
        outcome.exit_code = code
        outcome.stderr_tail = "\n".join(program.stderr)
        if gone and code is None:
            outcome.status += "; the program was ended"
        if not gone:
            outcome.status = "played every episode" + (
                "; it did not exit at the end of its input and was ended" if code is None
                else f"; exited with code {code}"
            )
        return outcome

    def _serve(
        self, program: _Program, referee: Referee, limit: float, outcome: PlayOutcome
    ) -> str:
        """Answer the program until the benchmark is over (""), or why it is gone."""
        owed = 0  # requests of its still to come for decisions made for it
        strikes = 0
        pending = time.monotonic()
        allowance = max(limit, STARTUP_S)
        while not referee.finished:
            left = pending + allowance - time.monotonic()
            # Past the deadline it is a time-out, however many lines wait (a flood of
            # requests that are not moves must not hold the clock).
            got: tuple[float, Any] = program.next_line(left) if left > 0 else (0.0, _TIMEOUT)
            received, item = got
            if item is _TIMEOUT:
                referee.timeout()
                owed += 1
                strikes += 1
                pending, allowance = time.monotonic(), limit
                if strikes >= MAX_STRIKES:
                    return f"it made no decision within {limit:g} s {strikes} times in a row"
                continue
            if item is _EOF:  # it exited, or closed its output: which, it says by exiting
                try:
                    code = program.process.wait(timeout=EXIT_GRACE_S)
                except subprocess.TimeoutExpired:
                    return "it closed its output"
                return f"it exited with code {code}"
            late = False
            if item is _TOO_LONG:
                referee.fouls.bad_requests += 1
                answer, moved, cmd = {"error": "line too long: not read"}, False, None
            else:
                cmd = _command_of(item)
                if owed and cmd in ("step", "reset"):
                    owed -= 1
                    answer = referee.current(
                        "this request came after its decision time; the default was played "
                        "for it, and this is the state now"
                    )
                    moved = late = True
                else:
                    answer, moved = referee.handle_line(item)
            if moved and cmd == "step" and not late:
                outcome.decision_times.append(received - pending)
            sending = time.monotonic()
            if not program.send((json.dumps(answer) + "\n").encode("ascii"), limit):
                return "it stopped reading its input"
            if moved:  # a new decision is due: its clock started as the answer went out
                pending, allowance, strikes = sending, limit, 0
        return ""


def _command_of(line: bytes) -> str | None:
    try:
        cmd = parse_request(line).get("cmd")
    except ValueError:
        return None
    return cmd if isinstance(cmd, str) else None
