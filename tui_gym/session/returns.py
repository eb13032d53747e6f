"""`return_range_of`: the returns one episode of a game can have, with the arguments and
wrappers a run was trained with (the game's oracle reads them off its model)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from functools import lru_cache
from typing import Any

from tui_gym.core.mdp import NotAvailable
from tui_gym.games import Game

__all__ = ["return_range_of"]

Range = tuple[float, float]


def return_range_of(
    game: Game, env_id: str, kwargs: Mapping[str, Any],
    wrappers: Iterable[tuple[str, Mapping[str, Any]]] = (),
) -> Range | None:
    """(lowest, highest) return of one episode of `game` as `env_id` with these arguments and
    wrappers (name, parameters), ±inf where unbounded; None when not known."""
    try:
        frozen = (tuple(sorted(kwargs.items())),
                  tuple((name, tuple(sorted(params.items()))) for name, params in wrappers))
        return _range(game, env_id, *frozen)
    except TypeError:  # a value that cannot be a key (a list from a file): not known
        return None


@lru_cache(maxsize=32)
def _range(
    game: Game, env_id: str, kwargs: tuple[tuple[str, Any], ...],
    wrappers: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...],
) -> Range | None:
    import gymnasium as gym

    from tui_gym.core.wrappers import WrapperChoice, build_env
    from tui_gym.core.wrappers.changes import GameChanges

    try:
        arguments = game.normalize_kwargs(dict(kwargs))
        choices = [WrapperChoice.make(name, **dict(params)) for name, params in wrappers]
        env = build_env(game.make_id(env_id, arguments), game.make_kwargs(arguments), choices)
    except (ValueError, TypeError, gym.error.Error):
        return None
    with env:
        changes = GameChanges.of(env, game.episode_limit(arguments))
    found = game.oracle.return_range(arguments, changes)
    return None if isinstance(found, NotAvailable) else found
