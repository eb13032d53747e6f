"""The arena's one seam to the games: the catalog, and a game's protocol handler (the
`JsonlPlayer` everything else in the arena talks to a game through)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from tui_gym.core.params import Param
from tui_gym.games import GAMES, Game, game_for, resolve_env_id
from tui_gym.session.protocol import JsonlPlayer


@dataclass(frozen=True)
class GameEntry:
    """One registered game as a program sees it: names, actions and parameters."""

    name: str  # the short alias, e.g. "blackjack"
    title: str
    env_id: str
    actions: tuple[str, ...]
    params: tuple[Param, ...]
    description: str

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name, "title": self.title, "env_id": self.env_id,
            "actions": list(self.actions),
            "parameters": [{"name": p.name, "type": p.kind.__name__, "default": p.default,
                            "range": p.describe_range(), "help": p.help} for p in self.params],
            "description": self.description,
        }


def _entry(game: Game) -> GameEntry:
    return GameEntry(name=game.name, title=game.title, env_id=game.env_id,
                     actions=tuple(game.action_names), params=tuple(game.params),
                     description=game.description)


def catalog() -> list[GameEntry]:
    """Every registered game, in the registry's order."""
    return [_entry(game) for game in GAMES]


def find_game(name: str, *, from_data: bool = False) -> GameEntry:
    """The game a short alias or Gymnasium id names; ValueError listing the games if none.
    `from_data`: the name came from a program (a tool call), so it never imports a module."""
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"name a game: one of {', '.join(e.name for e in catalog())}")
    return _entry(game_for(resolve_env_id(name, from_data=from_data)))


def open_handler(
    name: str, params: Mapping[str, Any] | None = None, seed: int | None = None,
    wrappers: Sequence[str] = (),
) -> JsonlPlayer:
    """A protocol handler playing game `name` with `params` and `wrappers` (`--wrapper` specs);
    ValueError with one clear line for a bad game, parameter or wrapper."""
    from tui_gym.core.wrappers import check_chain_length, parse_wrapper_spec
    from tui_gym.session.session import Session

    entry = find_game(name)
    check_chain_length(len(wrappers))
    choices = tuple(parse_wrapper_spec(spec) for spec in wrappers)
    session = Session(env_id=entry.env_id, env_kwargs=dict(params or {}), choices=choices,
                      seed=seed or 0)
    if session.skipped:
        session.env.close()
        reasons = "; ".join(reason for _, reason in session.skipped)
        raise ValueError(f"wrapper does not fit {entry.title}: {reasons}")
    return JsonlPlayer(session, seed=seed)
