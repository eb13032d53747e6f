"""`Referee`: one game served to a player under benchmark rules."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from tui_gym.core.experiments.figures import FieldsJson
from tui_gym.session.arena import Seat, SeatError, find_game, open_handler
from tui_gym.session.protocol import parse_request


@dataclass
class Fouls(FieldsJson):
    """What a player got wrong, counted."""

    invalid_actions: int = 0  # steps whose action was not valid (the default was played)
    timeouts: int = 0  # decisions not made in time (the default was played)
    defaulted: int = 0  # decisions made for a player that had exited or stopped answering
    bad_requests: int = 0  # lines that were not a usable request, or a request out of turn
    hints_refused: int = 0


@dataclass
class Referee:
    """Serves `episodes` episodes of a game, from seed `seed`, to one player."""

    game: str
    episodes: int
    seed: int
    params: dict[str, Any] = field(default_factory=dict)
    wrappers: tuple[str, ...] = ()
    allow_hints: bool = False

    def __post_init__(self) -> None:
        self.entry = find_game(self.game)
        handler = open_handler(self.entry.env_id, self.params, self.seed, self.wrappers)
        self.params = dict(handler.session.env_kwargs)  # defaults filled in
        self.seat = Seat(handler, self.entry, self.seed)
        self.fouls = Fouls()
        self.started = 0  # episodes started so far

    # -- the state of play ------------------------------------------------
    @property
    def finished(self) -> bool:
        """Whether every episode has been played to its end."""
        return self.started >= self.episodes and self.seat.done

    def default_action(self) -> str:
        return self.seat.legal_actions()[0]

    def _transition(self) -> dict[str, Any]:
        last = self.seat.last
        assert last is not None
        return dict(last)

    def _start_episode(self) -> dict[str, Any]:
        seed = self.seed + self.started
        self.seat.reset(seed)
        self.started += 1
        if self.started == 1 and not self.seat.done:
            self.seat.judge(self.default_action())  # the exact figures solved off the clock
        return {**self._transition(), "episode": self.started, "seed": seed}

    # -- requests -----------------------------------------------------------
    def handle_line(self, line: bytes | str) -> tuple[dict[str, Any], bool]:
        """Answer one request line; the answer, and whether it moved the game on (a step
        or the next episode's deal)."""
        try:
            request = parse_request(line)
        except ValueError as exc:
            self.fouls.bad_requests += 1
            return {"error": str(exc)}, False
        return self.handle(request)

    def handle(self, request: dict[str, Any]) -> tuple[dict[str, Any], bool]:
        """Answer one request object; the answer, and whether it moved the game on."""
        cmd = request.get("cmd")
        moved = False
        if cmd == "reset":
            answer, moved = self._reset()
        elif cmd == "step":
            answer, moved = self._step(request)
        elif cmd == "hint" and not self.allow_hints:
            self.fouls.hints_refused += 1
            answer = {"error": "hints are off during a benchmark (--allow-hints turns them on)"}
        else:
            answer = self.seat.handler.handle(json.dumps(request))
            if "error" in answer:
                self.fouls.bad_requests += 1
        if "id" in request and "id" not in answer:
            answer = {"id": request["id"], **answer}
        return answer, moved

    def _reset(self) -> tuple[dict[str, Any], bool]:
        if self.finished:
            self.fouls.bad_requests += 1
            return {"error": f"the benchmark is over: {self.episodes} episodes played"}, False
        if not self.seat.done:
            self.fouls.bad_requests += 1
            return {"error": "the episode is not over: a benchmark plays every episode to "
                             "its end"}, False
        return self._start_episode(), True

    def _step(self, request: dict[str, Any]) -> tuple[dict[str, Any], bool]:
        if self.seat.last is None or self.seat.done:
            self.fouls.bad_requests += 1
            word = "the benchmark is over" if self.finished else "the episode is over"
            return {"error": f"{word}: no move to make (reset starts the next episode)"}, False
        action = request.get("action")
        try:
            name = self.seat.action_name(action)  # type: ignore[arg-type]
        except SeatError as exc:
            self.fouls.invalid_actions += 1
            default = self.default_action()
            self.seat.step(default)
            return {**self._transition(), "invalid": f"{exc}; played {default}"}, True
        self.seat.step(name)
        return self._transition(), True

    def timeout(self) -> None:
        """Play for a player that did not decide in time."""
        self.fouls.timeouts += 1
        self._play_default()

    def play_default(self) -> None:
        """Play for a player that is gone (exited, or stopped answering)."""
        self.fouls.defaulted += 1
        self._play_default()

    def _play_default(self) -> None:
        """The default move, or the next episode's deal."""
        if self.finished:
            raise SeatError("the benchmark is over")
        if self.seat.done:
            self._start_episode()
        else:
            self.seat.step(self.default_action())

    def current(self, note: str) -> dict[str, Any]:
        """The state now, with a note (for a request the referee answered for the player)."""
        if self.seat.last is None:
            return {"error": note}
        return {**self._transition(), "late": note}

    def close(self) -> None:
        self.seat.close()
