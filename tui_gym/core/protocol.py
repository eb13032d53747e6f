"""The JSON-lines protocol: programs play the same games people do.

`JsonlPlayer.handle(line)` takes one request line and returns one response
object; `serve(stdin, stdout)` runs the loop behind `tui-gym play ENV --jsonl`
(one JSON object a line in, one a line out, flushed; end of input ends it).

Requests (an optional `"id"` is echoed back in the response):

- `{"cmd": "spaces"}`: observation and action spaces, action names, wrappers;
- `{"cmd": "reset"}` (optional `"seed"`): a new episode;
- `{"cmd": "step", "action": A}`: A as the integer or the action's name;
- `{"cmd": "render"}`: the text picture (hidden cards stay hidden);
- `{"cmd": "hint"}`: the exact optimal action(s) in the current state, in the
  game as its wrappers make it;
- `{"cmd": "help"}`: the list of commands.

Reset and step answer with `observation` (JSON-friendly), `reward`,
`terminated`, `truncated`, `info`. Any bad line gets `{"error": "..."}` and
the session goes on.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import IO, Any

from tui_gym.core.play import HumanGame, PlayError
from tui_gym.core.profiles.base import to_jsonable
from tui_gym.core.session import Session

COMMANDS = ("spaces", "reset", "step", "render", "hint", "help")


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


class JsonlPlayer:
    """Answers protocol requests for one game (with the session's wrappers)."""

    def __init__(self, session: Session, seed: int | None = None) -> None:
        self.session = session
        self.profile = session.profile
        self.game = HumanGame(session, seed=seed)
        self._handlers: dict[str, Callable[[dict[str, Any]], dict[str, Any]]] = {
            "spaces": self._spaces,
            "reset": self._reset,
            "step": self._step,
            "render": self._render,
            "hint": self._hint,
            "help": self._help,
        }

    def handle(self, line: str) -> dict[str, Any]:
        """One request line in, one response object out (never raises for bad input)."""
        try:
            request = json.loads(line)
        except json.JSONDecodeError as exc:
            return {"error": f"not JSON: {exc.msg} at column {exc.colno}"}
        if not isinstance(request, dict):
            return {"error": 'a request must be a JSON object like {"cmd": "reset"}'}
        cmd = request.get("cmd")
        handler = self._handlers.get(cmd) if isinstance(cmd, str) else None
        if handler is None:
            response = {"error": f"unknown cmd {cmd!r}; commands: {', '.join(COMMANDS)}"}
        else:
            try:
                response = handler(request)
            except PlayError as exc:
                response = {"error": str(exc)}
            except (ValueError, TypeError) as exc:
                response = {"error": str(exc)}
        if "id" in request:
            response = {"id": request["id"], **response}
        return _finite(response)

    def _transition(self) -> dict[str, Any]:
        step = self.game.last
        assert step is not None
        return {
            "observation": self.profile.json_observation(step.observation),
            "reward": step.reward,
            "terminated": step.terminated,
            "truncated": step.truncated,
            "info": to_jsonable(step.info),
        }

    def _spaces(self, request: dict[str, Any]) -> dict[str, Any]:
        env = self.game.env
        return {
            "env_id": self.session.env_id,
            "env_kwargs": self.session.env_kwargs,
            "wrappers": [str(c) for c in self.session.applied],
            "observation_space": str(env.observation_space),
            "action_space": str(env.action_space),
            "actions": list(self.profile.action_names),
        }

    def _reset(self, request: dict[str, Any]) -> dict[str, Any]:
        seed = request.get("seed")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        self.game.reset(seed=seed)
        return self._transition()

    def _step(self, request: dict[str, Any]) -> dict[str, Any]:
        if "action" not in request:
            names = ", ".join(self.profile.action_names)
            raise ValueError(f'step needs an "action": an integer or one of {names}')
        self.game.step(request["action"])
        return self._transition()

    def _render(self, request: dict[str, Any]) -> dict[str, Any]:
        if self.game.last is None:
            raise PlayError("no episode running: reset first")
        return {"text": self.game.text()}

    def _hint(self, request: dict[str, Any]) -> dict[str, Any]:
        if self.game.last is None:
            raise PlayError("no episode running: reset first")
        if self.game.done:
            raise PlayError("the episode is over: reset to play again")
        advice = self.profile.advice(self.game.env, self.session.env_kwargs)
        names = self.profile.action_names
        response: dict[str, Any] = {
            "optimal_actions": [names[a] for a in advice.optimal],
            "note": advice.note,
        }
        if advice.values is not None:
            response["action_values"] = {names[a]: v for a, v in advice.values.items()}
        if advice.unwrapped_optimal:  # the wrappers change the game beyond exact figures
            response["unwrapped_optimal_actions"] = [names[a] for a in advice.unwrapped_optimal]
        return response

    def _help(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"commands": list(COMMANDS), "actions": list(self.profile.action_names)}


def serve(player: JsonlPlayer, stdin: IO[str], stdout: IO[str]) -> int:
    """Answer every line of `stdin` on `stdout`; blank lines are skipped. Returns 0."""
    for line in stdin:
        if not line.strip():
            continue
        stdout.write(json.dumps(player.handle(line)) + "\n")
        stdout.flush()
    return 0
