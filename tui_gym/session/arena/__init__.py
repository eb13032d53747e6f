"""The arena: programs play the registered games and are scored decision by decision.

Every game is reached through one seam (`games`): the catalog of games and a
game's JSON-lines protocol handler. On top of it:

- `seat`: `Seat`, one game played through its handler, each move judged
  against the exact optimum before it is made;
- `score`: `Verdict` (one move's judgement) and `ArenaScore` (returns per
  episode, exact decision regret, agreement with the optimum);
- `table`: `GameTable`, several games at once, bounded in number, idle ones
  expiring on an injectable clock.

The exact decision regret of a move is `max_a Q*(s, a) - Q*(s, action)`, in
the game's expected return as its wrappers make it; summed over an episode it
is an unbiased, low-variance estimate of that episode's gap to the optimum.
Where a game gives no exact action values (or its wrappers change it beyond
them) the regret is unavailable and the score says so, rather than guess.
"""

from tui_gym.session.arena.games import GameEntry, catalog, find_game, open_handler
from tui_gym.session.arena.score import ArenaScore, EpisodeScore, Verdict
from tui_gym.session.arena.seat import Seat, SeatError
from tui_gym.session.arena.table import GameTable, TableError

__all__ = [
    "ArenaScore",
    "EpisodeScore",
    "GameEntry",
    "GameTable",
    "Seat",
    "SeatError",
    "TableError",
    "Verdict",
    "catalog",
    "find_game",
    "open_handler",
]
