"""The game a recording names, looked up in the games this tui-gym knows."""

from __future__ import annotations

from typing import Any


def game_named(env_id: str) -> Any | None:
    """The game that plays `env_id`, or None for one unknown (or that would import code)."""
    if not env_id:
        return None
    from tui_gym.games import game_for

    try:
        return game_for(env_id, from_data=True)
    except ValueError:
        return None
