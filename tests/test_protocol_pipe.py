"""The protocol with requests sent ahead of their answers: batched reading, answers in
order and flushed before the server waits, `auto_reset`, and the bench's pipe figures."""

from __future__ import annotations

import dataclasses
import io
import json
import random

from rich.console import Console

from tests.test_bench import fake_results
from tui_gym.bench import programs
from tui_gym.bench.programs import ProgramsResult, RateResult, RoundTripResult, SeparationResult
from tui_gym.bench.report import table, to_json
from tui_gym.session.protocol import JsonlPlayer, read_batches, serve
from tui_gym.session.session import Session


class Chunks(io.RawIOBase):
    """Input that arrives in the given pieces, one per read; logs each read to `log`."""

    def __init__(self, pieces: list[bytes], log: list[str]) -> None:
        self.pieces, self.log = list(pieces), log

    def read1(self, size: int = -1) -> bytes:
        self.log.append("read")
        return self.pieces.pop(0) if self.pieces else b""


class Answers(io.StringIO):
    def __init__(self, log: list[str]) -> None:
        super().__init__()
        self.log = log

    def flush(self) -> None:
        self.log.append(f"flush {self.getvalue().count(chr(10))}")


def test_lines_split_anywhere_come_back_whole_and_overlong_ones_as_none() -> None:
    lines = [b"a", b"", b"x" * 40, b"bcd", b"y" * 16, b"e" * 15]
    data = b"\n".join(lines) + b"\nlast"  # the last line has no newline
    rng = random.Random(3)
    for _ in range(20):
        cuts = sorted(rng.sample(range(1, len(data)), 6))
        pieces = [data[i:j] for i, j in zip([0, *cuts], [*cuts, len(data)], strict=True)]
        batches = list(read_batches(Chunks(pieces, []), limit=16))  # type: ignore[arg-type]
        assert all(batches)
        got = [line for batch in batches for line in batch]
        assert got == [b"a", b"", None, b"bcd", None, b"e" * 15, b"last"]


def test_answers_come_in_order_and_are_flushed_before_the_server_waits() -> None:
    log: list[str] = []
    first = b"".join(b'{"cmd":"help","id":%d}\n' % k for k in range(3))
    stdin = Chunks([first + b'{"cmd":"he', b'lp","id":3}\n\n'], log)
    stdout = Answers(log)
    assert serve(JsonlPlayer(Session("blackjack"), seed=0), stdin, stdout) == 0  # type: ignore[arg-type]
    assert log == ["read", "flush 3", "read", "flush 4", "read"]
    assert [json.loads(line)["id"] for line in stdout.getvalue().splitlines()] == [0, 1, 2, 3]


def test_auto_reset_starts_the_next_episode_in_the_answer() -> None:
    player = JsonlPlayer(Session("blackjack"), seed=0)
    player.handle('{"cmd": "reset", "seed": 7}')
    ended = player.handle('{"cmd": "step", "action": "stick", "auto_reset": true}')
    assert ended["terminated"] is True and ended["reward"] in (-1.0, 0.0, 1.0)
    fresh = ended["reset"]
    assert set(fresh) == {"observation", "reward", "terminated", "truncated", "info"}
    assert fresh["terminated"] is False and fresh["reward"] == 0.0
    going = player.handle('{"cmd": "step", "action": "hit", "auto_reset": true}')
    assert "error" not in going
    assert going.get("terminated") or "reset" not in going  # "reset" only when one ended
    assert "auto_reset must be true or false" in player.handle(
        '{"cmd": "step", "action": 0, "auto_reset": 1}')["error"]
    player.handle('{"cmd": "reset"}')
    player.handle('{"cmd": "step", "action": "stick"}')  # no auto_reset: the episode stays over
    assert "the episode is over" in player.handle('{"cmd": "step", "action": 0}')["error"]


def test_the_bench_measures_both_pipe_figures_and_reports_them() -> None:
    assert programs.measure_protocol(0.05, 1).samples[0] > 0
    trip = programs.measure_round_trip(0.05, 1)
    assert trip.round_trips > 0 and 0 < trip.p50_us <= trip.p95_us  # type: ignore[operator]
    separation = SeparationResult(20_000, 0.038, (0.953, 0.953), (0.0, 0.2), 0.04)
    found = ProgramsResult(separation, RateResult((30_000.0,)), RateResult((900.0,)),
                           RateResult((1_400.0,)),
                           RoundTripResult(80.0, 120.0, 5_000, RateResult((12_000.0,))))
    results = dataclasses.replace(fake_results(), programs=found)
    data = json.loads(json.dumps(to_json(results)))
    assert data["figures"]["protocol_round_trip_p50_us"] == 80.0
    assert data["programs"]["protocol_round_trip"]["rate"]["samples"] == [12_000.0]
    console = Console(record=True, width=200)
    console.print(table(results))
    text = console.export_text()
    assert f"{programs.WINDOW} requests in flight" in text
    assert "round trip p50" in text and "80 µs (p95 120; 12,000 steps/s)" in text
