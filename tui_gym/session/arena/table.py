"""`GameTable`: several games at once by increasing integer ids, bounded in number; one idle
for `idle_timeout` seconds is closed at the table's next use (and said to have expired)."""

from __future__ import annotations

import itertools
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from tui_gym.session.arena.games import find_game, open_handler
from tui_gym.session.arena.seat import Seat

REMEMBERED_ENDS = 1024  # ids of ended games remembered for a clear message


class TableError(ValueError):
    """A request the table refuses (unknown or expired game, too many games)."""


@dataclass
class _Entry:
    seat: Seat
    used: float


class GameTable:
    """The games a server plays at once."""

    def __init__(
        self, max_games: int = 8, idle_timeout: float = 600.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if max_games < 1:
            raise ValueError(f"max_games must be at least 1, got {max_games}")
        if not idle_timeout > 0:
            raise ValueError(f"idle_timeout must be positive, got {idle_timeout}")
        self.max_games = max_games
        self.idle_timeout = float(idle_timeout)
        self.clock = clock
        self._games: dict[int, _Entry] = {}
        self._ended: OrderedDict[int, str] = OrderedDict()  # id -> why it ended
        self._ids = itertools.count(1)

    def __len__(self) -> int:
        return len(self._games)

    def ids(self) -> list[int]:
        return sorted(self._games)

    def _forget(self, game_id: int, why: str) -> None:
        entry = self._games.pop(game_id)
        entry.seat.close()
        self._ended[game_id] = why
        while len(self._ended) > REMEMBERED_ENDS:
            self._ended.popitem(last=False)

    def expire(self) -> list[int]:
        """Close the games idle for longer than the timeout; their ids."""
        now = self.clock()
        idle = [i for i, e in self._games.items() if now - e.used > self.idle_timeout]
        for game_id in idle:
            self._forget(game_id, f"expired after {self.idle_timeout:g} s without a call")
        return idle

    def start(
        self, game: str, params: Mapping[str, Any] | None = None, seed: int | None = None,
        wrappers: Sequence[str] = (),
    ) -> tuple[int, Seat]:
        """Open a game and deal its first episode; its id and seat."""
        self.expire()
        if len(self._games) >= self.max_games:
            raise TableError(
                f"{len(self._games)} games are running, the most this server plays at once; "
                f"end one with end_game (running: {', '.join(map(str, self.ids()))}) or let "
                f"one stay idle for {self.idle_timeout:g} s to expire"
            )
        entry = find_game(game, from_data=True)  # a program's choice: never imports code
        seat = Seat(open_handler(entry.env_id, params, seed, wrappers), entry, seed)
        try:
            seat.reset()
        except ValueError:
            seat.close()
            raise
        game_id = next(self._ids)
        self._games[game_id] = _Entry(seat, self.clock())
        return game_id, seat

    def get(self, game_id: int) -> Seat:
        """The seat of a running game (marked as used now); TableError saying why if none."""
        self.expire()
        entry = self._games.get(game_id)
        if entry is None:
            why = self._ended.get(game_id)
            if why is not None:
                raise TableError(f"game {game_id} {why}; start a new one with start_game")
            running = ", ".join(map(str, self.ids())) or "none"
            raise TableError(f"no game {game_id}: start one with start_game (running: {running})")
        entry.used = self.clock()
        return entry.seat

    def end(self, game_id: int) -> Seat:
        """Close a game; its seat (for a final score)."""
        seat = self.get(game_id)
        self._forget(game_id, "was ended")
        return seat

    def close(self) -> None:
        for game_id in list(self._games):
            self._forget(game_id, "was closed")
