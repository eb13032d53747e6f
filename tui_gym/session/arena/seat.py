"""`Seat`: one game played through its protocol handler, each move judged (from the game's
hint) before it is made, whatever the player asked for."""

from __future__ import annotations

import contextlib
import json
from typing import Any

from tui_gym.session.arena.games import GameEntry
from tui_gym.session.arena.score import ArenaScore, Verdict
from tui_gym.session.protocol import JsonlPlayer


class SeatError(ValueError):
    """A request the game refused; the message is the game's own, for people."""


class Seat:
    """One game (a protocol handler) with the score of whoever plays it."""

    def __init__(self, handler: JsonlPlayer, entry: GameEntry, seed: int | None = None) -> None:
        self.handler = handler
        self.entry = entry
        self.seed = seed
        self.score = ArenaScore()
        self.last: dict[str, Any] | None = None  # the latest reset or step answer
        self._episodes = 0

    def ask(self, request: dict[str, Any]) -> dict[str, Any]:
        """Send one protocol request; SeatError with the game's message if it is refused."""
        answer = self.handler.handle(json.dumps(request))
        if "error" in answer:
            raise SeatError(str(answer["error"]))
        return answer

    @property
    def done(self) -> bool:
        last = self.last
        return last is None or bool(last["terminated"] or last["truncated"])

    def action_name(self, action: int | str) -> str:
        """The name of an action given by number or name; SeatError listing them if invalid."""
        names = self.entry.actions
        with contextlib.suppress(ValueError):
            return names[self.handler.rules.action_index(action)]
        valid = ", ".join(f"{i}={n}" for i, n in enumerate(names))
        shown = repr(action) if isinstance(action, str) else str(action)
        raise SeatError(f"invalid action {shown[:40]}; valid actions: {valid}")

    def reset(self, seed: int | None = None) -> dict[str, Any]:
        """Start an episode (the first uses the seat's seed unless `seed` is given)."""
        answer = self.ask({"cmd": "reset"} if seed is None else {"cmd": "reset", "seed": seed})
        used = seed if seed is not None else (self.seed if self._episodes == 0 else None)
        self._episodes += 1
        self.score.start_episode(used)
        self.last = answer
        return answer

    def judge(self, name: str) -> Verdict:
        """The verdict on taking action `name` in the current state (from the game's hint)."""
        try:
            return Verdict.from_hint(self.hint(), name)
        except SeatError as exc:
            return Verdict(False, note=str(exc))

    def step(self, action: int | str) -> tuple[dict[str, Any], Verdict]:
        """Make a move; its answer and its verdict. SeatError if the move is refused."""
        if self.last is None:
            raise SeatError("no episode running: reset first")
        if self.done:
            raise SeatError("the episode is over: reset to play again")
        name = self.action_name(action)
        verdict = self.judge(name)
        answer = self.ask({"cmd": "step", "action": name})
        self.last = answer
        done = bool(answer["terminated"] or answer["truncated"])
        self.score.record(verdict, float(answer["reward"]), done, bool(answer["terminated"]))
        return answer, verdict

    def legal_actions(self) -> list[str]:
        """The actions allowed now: all of them, or those an `action_mask` in the info allows."""
        names = list(self.entry.actions)
        info = (self.last or {}).get("info") or {}
        mask = info.get("action_mask") if isinstance(info, dict) else None
        if isinstance(mask, list) and len(mask) == len(names):
            return [n for n, allowed in zip(names, mask, strict=True) if allowed]
        return names

    def observe(self) -> dict[str, Any]:
        """The state now: as data and as text, the legal actions, and how the episode stands."""
        if self.last is None:
            raise SeatError("no episode running: reset first")
        episode = self.score.current
        last = self.last
        return {
            "observation": last["observation"], "text": self.ask({"cmd": "render"})["text"],
            "legal_actions": [] if self.done else self.legal_actions(),
            "last_reward": last["reward"], "terminated": last["terminated"],
            "truncated": last["truncated"], "done": self.done,
            "episode": episode.index if episode else 0, "steps": episode.steps if episode else 0,
            "episode_return": episode.episode_return if episode else 0.0, "info": last["info"],
        }

    def hint(self) -> dict[str, Any]:
        """The game's hint for the current state (exact action values where it has them)."""
        return self.ask({"cmd": "hint"})

    def close(self) -> None:
        """Close the envs the handler holds (its game's and its session's)."""
        self.handler.game.close()
        self.handler.session.env.close()
