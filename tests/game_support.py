"""Helpers for tests that drive engines directly: a built env's game and batched form."""

from __future__ import annotations

from typing import Any

from tui_gym.core.vector import BatchedForm
from tui_gym.games import Game, game_for


def game_of(env: Any) -> tuple[Game, dict[str, Any]]:
    """The game that plays a built env, and its arguments as read from the env."""
    game = game_for(env.unwrapped.spec.id)
    kwargs = {p.name: getattr(env.unwrapped, p.name) for p in game.params
              if hasattr(env.unwrapped, p.name)}
    return game, game.normalize_kwargs(kwargs)


def form_of(env: Any) -> BatchedForm:
    """The batched form of a built env's game, as a session hands it to the engine."""
    game, kwargs = game_of(env)
    form = game.batched_form(kwargs)
    assert isinstance(form, BatchedForm), form
    return form
