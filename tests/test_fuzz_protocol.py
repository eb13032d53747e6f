"""Fuzz: protocol lines. Every line a program can send gets one strict-JSON answer, and the
session goes on to the last line; seeded, so every run sends the same lines."""

from __future__ import annotations

import io
import json
import os
import random
import subprocess
import sys

import pytest

from tui_gym.session.protocol import MAX_LINE_BYTES, JsonlPlayer, serve
from tui_gym.session.session import Session

from .test_fuzz_params import nasty_text, nasty_value

SEED = 11
LINES = 300
CMDS = ["spaces", "reset", "step", "render", "hint", "help", "fly", "", "STEP"]


def _json_text(value: object) -> str:
    """JSON text of a value, NaN and Infinity written the way Python writes them."""
    try:
        return json.dumps(value)
    except (ValueError, RecursionError):
        return "null"


def nasty_line(rng: random.Random) -> bytes:
    """One line a buggy or hostile program might send (no newline inside)."""
    kind = rng.randrange(10)
    if kind <= 3:  # a request with a nasty field
        request: dict[str, object] = {"cmd": rng.choice(CMDS)}
        for field in rng.sample(["action", "seed", "id", "options"], rng.randint(0, 3)):
            request[field] = "@" + field
        text = json.dumps(request)
        for field in ("action", "seed", "id", "options"):
            text = text.replace(f'"@{field}"', _json_text(nasty_value(rng)))
        line = text.encode("utf-8", "surrogatepass")
    elif kind == 4:  # numbers far past what Python converts
        field = rng.choice(["action", "seed", "id"])
        digits = rng.choice([20, 64, 65, 4300, 4301, 10_000])
        line = f'{{"cmd": "step", "{field}": {rng.choice(["", "-"])}{"9" * digits}}}'.encode()
    elif kind == 5:  # nesting
        depth = rng.choice([33, 100, 500, 1000, 5000])
        inner = "[" * depth + "]" * depth
        line = rng.choice([inner, f'{{"cmd": "help", "id": {inner}}}']).encode()
    elif kind == 6:  # bytes that are not UTF-8, inside a request or alone
        junk = bytes(rng.choice([0x80, 0xC3, 0xED, 0xF8, 0xFF]) for _ in range(rng.randint(1, 3)))
        line = rng.choice([junk, b'{"cmd": "help", "id": "' + junk + b'"}'])
    elif kind == 7:  # escapes of lone surrogates and control characters
        escape = rng.choice(["\\ud800", "\\udfff", "\\u0000", "\\ud83d", "\\ud83d\\ude00"])
        line = f'{{"cmd": "{escape}", "id": "{escape}", "action": "{escape}"}}'.encode()
    elif kind == 8:  # broken JSON
        text = json.dumps({"cmd": "step", "action": nasty_text(rng)})
        line = text[: rng.randrange(len(text))].encode("utf-8", "surrogatepass")
    else:  # random bytes
        line = bytes(rng.randrange(256) for _ in range(rng.randint(0, 40)))
    return line.replace(b"\n", b" ").replace(b"\r", b" ")


def nasty_lines(seed: int, count: int) -> list[bytes]:
    rng = random.Random(seed)
    lines = [nasty_line(rng) for _ in range(count)]
    lines.insert(count // 2, b'{"cmd": "help", "id": "' + b"x" * (MAX_LINE_BYTES + 1) + b'"}')
    return lines


def strict_json(line: bytes) -> dict:
    """A response as a strict reader reads it: ASCII, no NaN or Infinity, no lone surrogates."""

    def refuse(name: str) -> None:
        raise AssertionError(f"{name} in a response")

    value = json.loads(line.decode("ascii"), parse_constant=refuse)
    json.dumps(value, ensure_ascii=False).encode("utf-8")  # raises on a lone surrogate
    assert isinstance(value, dict) and value
    return value


def _lines() -> list[bytes]:
    return [b'{"cmd": "reset", "seed": 1}', *nasty_lines(SEED, LINES),
            b'{"cmd": "help", "id": "end"}']


def _check_answers(lines: list[bytes], answers: list[bytes]) -> None:
    """One strict-JSON answer a line that is not blank, errors on one short line, and the
    session still answering at the last line."""
    responses = [strict_json(line) for line in answers]
    asked = [line for line in lines if line.strip()]  # blank lines are skipped
    assert len(responses) == len(asked)
    assert responses[-1]["id"] == "end" and responses[-1]["commands"]
    for response in responses:
        if "error" in response:
            assert "\n" not in response["error"] and len(response["error"]) < 300
            assert "Traceback" not in response["error"]


def test_every_line_is_answered_and_the_session_goes_on() -> None:
    """Through the command's own pipes and encoding; every game's lines in process below."""
    lines = _lines()
    proc = subprocess.run(
        [sys.executable, "-m", "tui_gym", "play", "blackjack", "--jsonl", "--seed", "0"],
        input=b"".join(line + b"\n" for line in lines),
        capture_output=True,
        timeout=120,
        env={**os.environ, "LC_ALL": "C.UTF-8"},
    )
    assert proc.returncode == 0, proc.stderr.decode(errors="replace")[-2000:]
    assert proc.stderr == b""
    _check_answers(lines, proc.stdout.splitlines())


@pytest.mark.parametrize("game", ["blackjack", "gridworld"])
def test_every_line_is_answered_by_the_commands_loop_in_process(game: str) -> None:
    lines = _lines()
    out = io.StringIO()
    stdin = io.BytesIO(b"".join(line + b"\n" for line in lines))
    assert serve(JsonlPlayer(Session(game), seed=0), stdin, out) == 0
    _check_answers(lines, out.getvalue().encode().splitlines())


def test_the_player_answers_every_line_in_process() -> None:
    player = JsonlPlayer(Session("blackjack"), seed=0)
    player.handle('{"cmd": "reset"}')
    for line in nasty_lines(SEED + 1, LINES):
        response = player.handle(line)
        strict_json(json.dumps(response).encode())
