"""The JSON-lines protocol (see the README): programs play the same games people do; a bad
line gets `{"error": "..."}` and the session goes on."""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Callable, Iterator
from typing import IO, Any

from tui_gym.core.params import shown_value
from tui_gym.core.text import json_safe, nested_deeper
from tui_gym.games.words import to_jsonable
from tui_gym.session.play import HumanGame, PlayError
from tui_gym.session.session import Session

COMMANDS = ("spaces", "reset", "step", "render", "hint", "help")

MAX_LINE_BYTES = 1 << 20  # a request is a few dozen bytes; longer lines are refused, not held
MAX_DEPTH = 32  # nesting of arrays and objects in a request
MAX_INT_DIGITS = 64  # integer literals in a request (ids, seeds, actions)
MAX_SEED = 2**64 - 1
_ENCODER = json.JSONEncoder(allow_nan=False)  # once: `json.dumps` with options builds one a call
_PLAIN = (str, int, float, bool, type(None))
_CACHED_LINE_BYTES = 256  # a program repeats a handful of short requests: each is parsed once


class _BadNumber(ValueError):
    """A number in a request that is not read (too many digits, NaN, Infinity)."""


def _parse_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise _BadNumber(f"an integer of {len(text.lstrip('-')):,} digits is too long "
                         f"(at most {MAX_INT_DIGITS})")
    return int(text)


def _parse_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _BadNumber(f"{shown_value(text)} is beyond the range of a number")
    return value


def _parse_constant(name: str) -> float:
    raise _BadNumber(f"{name} is not a JSON number")


_DECODER = json.JSONDecoder(parse_int=_parse_int, parse_float=_parse_float,
                            parse_constant=_parse_constant)


def _clean_text(value: Any) -> str | None:
    """`value` as JSON text when it is JSON-safe as it is (no NaN or infinity, no surrogate
    in any text), else None: one pass of the C encoder, which most responses need alone."""
    try:
        text = _ENCODER.encode(value)
    except (TypeError, ValueError):
        return None
    return None if "\\ud" in text else text  # the encoder writes every surrogate as \udXXX


def parse_request(line: str | bytes) -> dict[str, Any]:
    """A request line as the JSON object it holds; ValueError saying why it is not one
    (not UTF-8, not JSON, not an object, nested too deeply, a number too long)."""
    short = len(line) <= _CACHED_LINE_BYTES
    return dict(_parse_cached(line) if short else _parse(line))  # a copy: the caller may change it


def _parse(line: str | bytes) -> dict[str, Any]:
    if isinstance(line, bytes):
        try:
            line = line.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ValueError(f"not UTF-8: byte 0x{line[exc.start]:02x} at column "
                             f"{exc.start + 1} cannot be decoded") from None
    try:  # messages with no internals in them
        if line.startswith("\ufeff"):  # json.loads names the byte-order mark
            request = json.loads(line, cls=json.JSONDecoder)
        else:
            request = _DECODER.decode(line)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not JSON: {exc.msg} at column {exc.colno}") from None
    except _BadNumber as exc:
        raise ValueError(f"not a usable request: {exc}") from None
    except RecursionError:
        raise ValueError(f"not a usable request: nested deeper than {MAX_DEPTH} levels") from None
    if not isinstance(request, dict):
        raise ValueError('a request must be a JSON object like {"cmd": "reset"}')
    # Fewer brackets than levels cannot nest too deep: most requests skip the walk.
    if line.count("[") + line.count("{") > MAX_DEPTH and nested_deeper(request, MAX_DEPTH):
        raise ValueError(f"not a usable request: nested deeper than {MAX_DEPTH} levels")
    return request


_parse_cached = functools.lru_cache(maxsize=1024)(_parse)


class JsonlPlayer:
    """Answers protocol requests for one game (with the session's wrappers)."""

    def __init__(self, session: Session, seed: int | None = None) -> None:
        self.session = session
        self.rules = session.game  # the game's names and roles
        self.game = HumanGame(session, seed=seed)

    def handle(self, line: str | bytes) -> dict[str, Any]:
        """One request line in, one response object out (never raises for bad input)."""
        response = self._respond(line)
        return response if _clean_text(response) is not None else json_safe(response)

    def handle_text(self, line: str | bytes) -> str:
        """`handle`, answered as the JSON text of the response (no newline)."""
        response = self._respond(line)
        text = _clean_text(response)
        return text if text is not None else json.dumps(json_safe(response))

    def _respond(self, line: str | bytes) -> dict[str, Any]:
        try:
            request = parse_request(line)
        except ValueError as exc:
            return {"error": str(exc)}
        cmd = request.get("cmd")
        handler: Callable[[dict[str, Any]], dict[str, Any]] | None = (
            getattr(self, f"_{cmd}") if cmd in COMMANDS else None)
        if handler is None:
            response = {"error": f"unknown cmd {shown_value(cmd)}; commands: {', '.join(COMMANDS)}"}
        else:
            try:
                response = handler(request)
            except (ValueError, TypeError) as exc:  # a PlayError too
                response = {"error": str(exc)}
        if "id" in request:
            response = {"id": request["id"], **response}
        return response

    def _transition(self) -> dict[str, Any]:
        step = self.game.last
        assert step is not None
        info = step.info
        if not all(type(k) is str and type(v) in _PLAIN for k, v in info.items()):
            info = to_jsonable(info)
        return {
            "observation": self.rules.states.json_observation(step.observation),
            "reward": step.reward, "terminated": step.terminated, "truncated": step.truncated,
            "info": info,
        }

    def _spaces(self, request: dict[str, Any]) -> dict[str, Any]:
        env = self.game.env
        return {
            "env_id": self.session.env_id, "env_kwargs": self.session.env_kwargs,
            "wrappers": [str(c) for c in self.session.applied],
            "observation_space": str(env.observation_space), "action_space": str(env.action_space),
            "actions": list(self.rules.action_names),
        }

    def _reset(self, request: dict[str, Any]) -> dict[str, Any]:
        seed = request.get("seed")
        if seed is not None and not (type(seed) is int and 0 <= seed <= MAX_SEED):  # not a bool
            raise ValueError(f"seed must be an integer in [0, {MAX_SEED}], got {shown_value(seed)}")
        self.game.reset(seed=seed)
        return self._transition()

    def _step(self, request: dict[str, Any]) -> dict[str, Any]:
        names = ", ".join(self.rules.action_names)
        if "action" not in request:
            raise ValueError(f'step needs an "action": an integer or one of {names}')
        action = request["action"]
        if not isinstance(action, int | str) or len(str(action)) > 32:
            valid = ", ".join(f"{i}={n}" for i, n in enumerate(self.rules.action_names))
            raise ValueError(f"invalid action {shown_value(action)}; valid actions: {valid}")
        auto_reset = request.get("auto_reset", False)
        if not isinstance(auto_reset, bool):
            raise ValueError(f"auto_reset must be true or false, got {shown_value(auto_reset)}")
        self.game.step(action)
        response = self._transition()
        if auto_reset and self.game.done:
            self.game.reset()
            response["reset"] = self._transition()
        return response

    def _render(self, request: dict[str, Any]) -> dict[str, Any]:
        if self.game.last is None:
            raise PlayError("no episode running: reset first")
        return {"text": self.game.text()}

    def _hint(self, request: dict[str, Any]) -> dict[str, Any]:
        if self.game.last is None:
            raise PlayError("no episode running: reset first")
        if self.game.done:
            raise PlayError("the episode is over: reset to play again")
        advice = self.rules.oracle.advice(self.game.env, self.session.env_kwargs)
        names = self.rules.action_names
        response: dict[str, Any] = {
            "optimal_actions": [names[a] for a in advice.optimal], "note": advice.note,
        }
        if advice.values is not None:
            response["action_values"] = {names[a]: v for a, v in advice.values.items()}
        if advice.unwrapped_optimal:  # the wrappers change the game beyond exact figures
            response["unwrapped_optimal_actions"] = [names[a] for a in advice.unwrapped_optimal]
        return response

    def _help(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"commands": list(COMMANDS), "actions": list(self.rules.action_names)}


def read_batches(stdin: IO[bytes], limit: int = MAX_LINE_BYTES,
                 chunk: int = 1 << 16) -> Iterator[list[bytes | None]]:
    """The lines of `stdin` in batches of those complete in what had arrived (a reader waits
    only when no whole line is left); a line longer than `limit` comes back as None."""
    read = getattr(stdin, "read1", stdin.read)  # read1: what has arrived, without waiting for more
    pending = b""  # the start of a line whose newline has not come yet
    dropping = False  # inside a line that is too long, until its newline
    while True:
        data = read(chunk)
        if not data:
            if dropping:
                yield [None]
            elif pending:
                yield [pending]
            return
        batch: list[bytes | None] = []
        if dropping:
            end = data.find(b"\n")
            if end < 0:
                continue
            batch.append(None)
            data, dropping = data[end + 1:], False
        lines = (pending + data).split(b"\n") if pending else data.split(b"\n")
        pending = lines.pop()
        batch.extend(line if len(line) < limit else None for line in lines)
        if len(pending) >= limit:
            pending, dropping = b"", True
        if batch:
            yield batch


def serve(player: JsonlPlayer, stdin: IO[bytes], stdout: IO[str]) -> int:
    """Answer every non-blank line of `stdin` (bytes, decoded line by line) on `stdout`, in
    order, the answers to lines that arrived together flushed together; returns 0."""
    too_long = json.dumps({"error": f"line longer than {MAX_LINE_BYTES:,} bytes: not read"})
    for batch in read_batches(stdin):
        answers = [too_long if line is None else player.handle_text(line)
                   for line in batch if line is None or line.strip()]
        if answers:
            answers.append("")
            stdout.write("\n".join(answers))
            stdout.flush()
    return 0
