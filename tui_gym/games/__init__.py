"""The games, one folder each, and the `GAMES` registry.

Ids that came from data (`from_data=True`) name registered games only: a file never
makes tui-gym import code.
"""

from __future__ import annotations

import importlib
import sys

from tui_gym.core.text import visible
from tui_gym.games.ab_grid import ABGridGame
from tui_gym.games.base import Game
from tui_gym.games.blackjack import BlackjackGame
from tui_gym.games.car_rental import CarRentalGame
from tui_gym.games.cliffwalking import CliffWalkingGame
from tui_gym.games.corner_grid import CornerGridGame
from tui_gym.games.dyna_maze import BlockingMazeGame, DynaMazeGame, ShortcutMazeGame
from tui_gym.games.frozenlake import FrozenLakeGame
from tui_gym.games.gambler import GamblerGame
from tui_gym.games.gridworld import GridWorldGame
from tui_gym.games.max_bias import MaxBiasGame
from tui_gym.games.random_walk import RandomWalkGame
from tui_gym.games.taxi import TaxiGame
from tui_gym.games.windy import KingWindyGame, WindyGame

__all__ = [
    "GAMES", "Game", "ImportRefusedError", "UnknownGameError", "game_for", "game_named",
    "resolve_env_id",
]

GAMES: tuple[Game, ...] = (
    BlackjackGame(), GridWorldGame(), FrozenLakeGame(), CliffWalkingGame(), TaxiGame(),
    ABGridGame(), CornerGridGame(), GamblerGame(), CarRentalGame(), RandomWalkGame(), WindyGame(),
    KingWindyGame(), DynaMazeGame(), BlockingMazeGame(), ShortcutMazeGame(), MaxBiasGame(),
)

_generic: dict[str, Game] = {}


class UnknownGameError(ValueError):
    """An env id or alias that no game plays; the message says why in one line."""


class ImportRefusedError(UnknownGameError):
    """A `module:Id` from data whose module is not imported: data never imports code."""


def game_named(name: str) -> Game:
    """A registered game by its alias (`UnknownGameError` for another)."""
    for game in GAMES:
        if game.name == name:
            return game
    raise UnknownGameError(f"no game named {name!r}")


MAX_ID_CHARS = 200  # no alias or Gymnasium id is longer


def resolve_env_id(name: str, *, from_data: bool = False) -> str:
    """An alias (`blackjack`, `taxi`, ...) or a Gymnasium id (`module:Id` imports the
    module, unless `from_data`: text from a file or a program) as the id a session builds."""
    if not isinstance(name, str):
        raise UnknownGameError(f"a game id is text, not a {type(name).__name__}")
    text = name.strip()
    if len(text) > MAX_ID_CHARS:
        raise UnknownGameError(f"no game has an id of {len(text):,} characters "
                               f"({visible(text, 40)})")
    for game in GAMES:
        if game.name == text.lower() or game.matches(text):
            return game.env_id if game.name == text.lower() else text
    module = text.rpartition(":")[0]
    if from_data and module and module not in sys.modules:
        raise ImportRefusedError(
            f"{visible(text, 60)} would import the module {visible(module, 40)}, and ids from "
            f"files and programs never import code; to play it on purpose, name it yourself: "
            f"tui-gym --env {visible(text, 60)} ..."
        )
    if text not in _generic:
        _check_generic(text)
    return text


def game_for(env_id: str, *, from_data: bool = False) -> Game:
    """The game that plays an env id (aliases accepted); `from_data` as for
    `resolve_env_id`."""
    env_id = resolve_env_id(env_id, from_data=from_data)
    for game in GAMES:
        if game.matches(env_id):
            return game
    if env_id not in _generic:
        from tui_gym.games.generic import GenericGame

        _generic[env_id] = GenericGame(env_id)
    return _generic[env_id]


def _check_generic(env_id: str) -> None:
    import gymnasium as gym

    import tui_gym.envs

    tui_gym.envs.register_envs()
    module, _, bare = env_id.rpartition(":")
    if module:
        try:
            importlib.import_module(module)
        except ImportError as error:
            raise UnknownGameError(f"cannot import {module!r} for {env_id!r}: {error}") from None
    if bare not in gym.registry:
        aliases = ", ".join(g.name for g in GAMES)
        from tui_gym.core.wrappers import UnknownEnvError

        raise UnknownGameError(f"{UnknownEnvError(bare)}; the games: {aliases}") from None
    from tui_gym.games.generic import check_fit

    misfit = check_fit(env_id)
    if misfit is not None:
        raise UnknownGameError(misfit.reason)
