"""Game profiles and how to find one by env id or short alias."""

from __future__ import annotations

from tui_gym.core.profiles.base import EvalOutcome, GameProfile, ReferenceMetrics
from tui_gym.games.blackjack.game import BlackjackProfile
from tui_gym.games.gridworld.game import GridWorldProfile

PROFILES: tuple[GameProfile, ...] = (BlackjackProfile(), GridWorldProfile())
ALIASES: dict[str, str] = {p.name: p.env_id for p in PROFILES}


class UnknownGameError(ValueError):
    """An env id or alias that no profile plays."""


def resolve_env_id(name: str) -> str:
    """A short alias (`blackjack`, `gridworld`) or a Gymnasium id, as a Gymnasium id."""
    text = name.strip()
    alias = ALIASES.get(text.lower())
    if alias:
        return alias
    for profile in PROFILES:
        if profile.matches(text):
            return text
    known = ", ".join(sorted(ALIASES) + [p.env_id for p in PROFILES])
    raise UnknownGameError(f"unknown env {name!r}; choose one of: {known}")


def profile_for(env_id: str) -> GameProfile:
    """The profile that plays an env id (aliases accepted)."""
    env_id = resolve_env_id(env_id)
    for profile in PROFILES:
        if profile.matches(env_id):
            return profile
    raise UnknownGameError(f"no game profile for {env_id!r}")


__all__ = [
    "ALIASES",
    "PROFILES",
    "EvalOutcome",
    "GameProfile",
    "ReferenceMetrics",
    "UnknownGameError",
    "profile_for",
    "resolve_env_id",
]
