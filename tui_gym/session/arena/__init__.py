"""The arena: programs play the registered games and are scored decision by decision."""

from tui_gym.session.arena.games import catalog, find_game, open_handler
from tui_gym.session.arena.score import ArenaScore, EpisodeScore, Verdict
from tui_gym.session.arena.seat import Seat, SeatError
from tui_gym.session.arena.table import GameTable, TableError

__all__ = [
    "ArenaScore", "EpisodeScore", "GameTable", "Seat", "SeatError", "TableError", "Verdict",
    "catalog", "find_game", "open_handler",
]
