"""The JSON-lines protocol, driven as a program would: lines in, one response a line out.
The command runs in this process (`main` on a stdin of bytes) where the game's answers are
the point, and as a subprocess where the process's own pipes, encoding and exit are."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import pytest

from tui_gym.cli import main
from tui_gym.games.blackjack.solver import BlackjackRules, optimal_policy
from tui_gym.session.protocol import JsonlPlayer
from tui_gym.session.session import Session


@pytest.fixture
def run_protocol(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]):
    """`play ENV --jsonl EXTRA` in this process, fed `lines`: responses, stderr, exit code."""

    def run(env: str, lines: list[str], *extra: str) -> tuple[list[dict], str, int]:
        data = "".join(line + "\n" for line in lines).encode()
        monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))
        try:
            code = main(["play", env, "--jsonl", *extra])
        except SystemExit as exit_:  # argparse's errors exit this way
            code = exit_.code
        out, err = capsys.readouterr()
        return [json.loads(line) for line in out.splitlines()], err, code

    return run


def test_blackjack_session_with_bad_lines_goes_on(run_protocol):
    lines = [
        '{"cmd": "spaces"}',
        '{"cmd": "step", "action": "hit"}',  # before reset
        "this is not json",
        "[1, 2]",
        '{"cmd": "fly", "id": 7}',
        '{"cmd": "reset", "seed": 5}',
        '{"cmd": "hint"}',
        '{"cmd": "step", "action": "jump"}',
        '{"cmd": "step"}',
        '{"cmd": "render"}',
        '{"cmd": "step", "action": "stick"}',
        '{"cmd": "step", "action": 1}',  # after the end
    ]
    responses, stderr, code = run_protocol("blackjack", lines, "--seed", "3")
    assert code == 0, stderr
    assert "Traceback" not in stderr
    assert len(responses) == len(lines)  # one response a line
    spaces = responses[0]
    assert spaces["actions"] == ["stick", "hit"]
    assert spaces["action_space"] == "Discrete(2)"
    for bad in (1, 2, 3, 7, 8, 11):
        assert set(responses[bad]) == {"error"}, responses[bad]
    assert responses[4] == {"id": 7, "error": responses[4]["error"]}
    reset = responses[5]
    assert set(reset) >= {"observation", "reward", "terminated", "truncated", "info"}
    player, dealer, usable = reset["observation"]
    hint = responses[6]
    best = optimal_policy(BlackjackRules())[player, dealer, usable]
    assert hint["optimal_actions"] == [("stick", "hit")[best]]
    assert set(hint["action_values"]) == {"stick", "hit"}
    assert "dealer" in responses[9]["text"] and "??" in responses[9]["text"]
    final = responses[10]
    assert final["terminated"] is True
    assert final["reward"] in (-1.0, 0.0, 1.0)


def test_gridworld_program_walks_to_the_target(run_protocol):
    # Reset first to learn the positions, then plan the walk in-process with the same seed.
    session = Session("gridworld", seed=0)
    probe = JsonlPlayer(session, seed=11)
    start = probe.handle('{"cmd": "reset"}')["observation"]
    (ax, ay), (tx, ty) = start["agent"], start["target"]
    moves = ["right" if tx > ax else "left"] * abs(tx - ax)
    moves += ["up" if ty > ay else "down"] * abs(ty - ay)
    lines = ['{"cmd": "reset"}']
    lines += [json.dumps({"cmd": "step", "action": m}) for m in moves]
    lines += ['{"cmd": "hint"}']
    responses, stderr, code = run_protocol("gridworld", lines, "--seed", "11")
    assert code == 0, stderr
    assert responses[0]["observation"] == start
    assert responses[-2]["terminated"] is True and responses[-2]["reward"] == 1.0
    assert responses[-2]["info"]["distance"] == 0
    assert "error" in responses[-1]  # no hint after the end


def test_integer_actions_and_wrappers_apply(run_protocol):
    lines = ['{"cmd": "spaces"}', '{"cmd": "reset", "seed": 1}', '{"cmd": "step", "action": 0}']
    responses, stderr, code = run_protocol(
        "gridworld", lines, "--wrapper", "StepPenalty:penalty=0.5"
    )
    assert code == 0, stderr
    assert responses[0]["wrappers"] == ["StepPenalty:penalty=0.5"]
    assert responses[1]["observation"] == {"agent": [2, 2], "target": [3, 4]}
    assert responses[2]["observation"]["agent"] == [3, 2]  # 0 is right: +x
    assert responses[2]["reward"] == pytest.approx(-0.5)


def test_bad_arguments_exit_2_with_one_line(run_protocol):
    responses, stderr, code = run_protocol("chess", [])
    assert code == 2 and responses == []
    assert len(stderr.strip().splitlines()) == 1
    assert "chess" in stderr


def test_end_of_input_exits_zero():
    proc = subprocess.run([sys.executable, "-m", "tui_gym", "play", "blackjack", "--jsonl"],
                          input="", capture_output=True, text=True, timeout=60)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")


@pytest.mark.parametrize(
    "request_line", ['{"cmd": "reset", "seed": -1}', '{"cmd": "reset", "seed": "x"}']
)
def test_bad_seed_is_an_error_response(request_line):
    player = JsonlPlayer(Session("blackjack"), seed=0)
    assert "error" in player.handle(request_line)


# -- hostile input: every line is answered, and the session goes on ---------------------------


def run_protocol_bytes(env: str, data: bytes, *extra: str) -> tuple[list[bytes], str, int]:
    """The real command, fed raw bytes under a strict UTF-8 locale; raw response lines."""
    proc = subprocess.run(
        [sys.executable, "-m", "tui_gym", "play", env, "--jsonl", *extra],
        input=data,
        capture_output=True,
        timeout=60,
        env={**os.environ, "LC_ALL": "C.UTF-8", "PYTHONIOENCODING": "utf-8:strict"},
    )
    return proc.stdout.splitlines(), proc.stderr.decode(errors="replace"), proc.returncode


def strict_json(line: bytes) -> dict:
    """A response as a strict reader reads it: ASCII, no NaN, no lone surrogates."""
    text = line.decode("ascii")

    def refuse(name: str) -> None:
        raise AssertionError(f"{name} in {text}")

    value = json.loads(text, parse_constant=refuse)
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            item.encode("utf-8")  # raises on a lone surrogate
        elif isinstance(item, dict):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)
    assert isinstance(value, dict)
    return value




HOSTILE = {
    "nested 1000 deep": b"[" * 1000 + b"]" * 1000,
    "nested 500 deep in id": b'{"cmd": "help", "id": ' + b"[" * 500 + b"]" * 500 + b"}",
    "5000-digit action": b'{"cmd": "step", "action": ' + b"7" * 5000 + b"}",
    "5000-digit seed": b'{"cmd": "reset", "seed": ' + b"7" * 5000 + b"}",
    "5000-digit id": b'{"cmd": "help", "id": ' + b"7" * 5000 + b"}",
    "NaN id": b'{"cmd": "help", "id": NaN}',
    "1e999 seed": b'{"cmd": "reset", "seed": 1e999}',
    "lone surrogates": b'{"cmd": "\\ud800", "id": "\\udcff"}',
    "invalid UTF-8 in a string": b'{"cmd": "help", "id": "\xc3\x28"}',
    "overlong line": b'{"cmd": "help", "id": "' + b"x" * (2 << 20) + b'"}',
    "seed beyond 64 bits": b'{"cmd": "reset", "seed": 18446744073709551616}',
}
AFTER_RESET = {
    "arabic-indic digit action": '{"cmd": "step", "action": "\u0661"}'.encode(),
    "superscript action": '{"cmd": "step", "action": "\u00b2"}'.encode(),
    "5000-character digit action": b'{"cmd": "step", "action": "' + b"0" * 5000 + b'1"}',
    "action a list": b'{"cmd": "step", "action": [1]}',
}


BAD_BYTE = [b'{"cmd":"help","id":1}', b"\xff", b'{"cmd":"help","id":3}']
HOSTILE_LINES = [*HOSTILE.values(), b'{"cmd": "reset", "seed": 7}', *AFTER_RESET.values(),
                 b'{"cmd": "step", "action": "stick", "id": "last"}']


@pytest.fixture(scope="module")
def hostile_run() -> tuple[list[dict], str, int]:
    """One strict-locale command fed a bad byte between two lines, then the hostile lines:
    every response read strictly, stderr, exit code."""
    lines = [*BAD_BYTE, *HOSTILE_LINES]
    raw, stderr, code = run_protocol_bytes("blackjack", b"".join(line + b"\n" for line in lines))
    return [strict_json(line) for line in raw], stderr, code


# One worker runs both tests of the one command above (xdist groups).
@pytest.mark.xdist_group("protocol_hostile")
def test_a_bad_byte_costs_one_line_and_earlier_lines_are_answered(hostile_run):
    answered, stderr, code = hostile_run
    assert code == 0, stderr
    responses = answered[: len(BAD_BYTE)]
    assert [r.get("id") for r in responses] == [1, None, 3]
    assert responses[1] == {"error": "not UTF-8: byte 0xff at column 1 cannot be decoded"}


@pytest.mark.xdist_group("protocol_hostile")
def test_hostile_lines_get_errors_and_the_session_goes_on(hostile_run):
    answered, stderr, code = hostile_run
    assert code == 0, stderr
    assert stderr == ""
    assert len(answered) == len(BAD_BYTE) + len(HOSTILE_LINES)
    responses = answered[len(BAD_BYTE):]
    for name, response in zip([*HOSTILE, "reset", *AFTER_RESET], responses, strict=False):
        if name != "reset":
            assert set(response) <= {"error", "id"} and response["error"], (name, response)
            for internal in ("Exceeds the limit", "invalid literal", "Traceback", "recursion"):
                assert internal not in response["error"], (name, response)
    reset = responses[len(HOSTILE)]
    assert reset["observation"] == [19, 10, 0]  # as in the README's transcript
    assert responses[-1]["id"] == "last" and responses[-1]["terminated"] is True
    named = dict(zip(HOSTILE, responses, strict=False))
    assert "nested deeper than" in named["nested 500 deep in id"]["error"]
    assert "5,000 digits is too long" in named["5000-digit seed"]["error"]
    assert named["lone surrogates"]["id"] == "\ufffd"
    assert "longer than 1,048,576 bytes" in named["overlong line"]["error"]
    assert "invalid action" in responses[len(HOSTILE) + 1]["error"]
