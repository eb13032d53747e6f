"""Programs as players: how many episodes exact-regret scoring needs, and protocol speeds."""

from __future__ import annotations

import math
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.bench.figures import median, percentile
from tui_gym.benchmark.players import InProcessPlayer, OptimalPlayer
from tui_gym.benchmark.referee import Referee
from tui_gym.benchmark.results import run_benchmark

Z95 = 1.96
DEVIATION = 0.05
MCP_GAMES = 4  # games one client plays at once for the MCP throughput
WINDOW = 64  # step requests the pipelined client keeps in flight
STEP_LINES = (b'{"cmd":"step","action":"up","auto_reset":true}\n',
              b'{"cmd":"step","action":"down","auto_reset":true}\n')


class DeviatingPlayer(InProcessPlayer):
    """The optimal player, except that on a share of decisions it takes a non-optimal action."""

    def __init__(self, share: float, seed: int) -> None:
        self.share = share
        self.rng = np.random.default_rng(seed)
        self.label = f"optimal, deviating on {share:.0%} of decisions"

    def choose(self, referee: Referee) -> str:
        hint = referee.seat.hint()
        optimal = list(hint.get("optimal_actions") or ())
        worse = [a for a in referee.seat.legal_actions() if a not in optimal]
        if worse and self.rng.random() < self.share:
            return worse[int(self.rng.integers(len(worse)))]
        return optimal[0] if optimal else referee.default_action()


def episodes_needed(sd_a: float, sd_b: float, delta: float) -> float:
    """Episodes per player for a 95% separation of two means `delta` apart."""
    if delta <= 0:
        return math.inf
    return Z95**2 * (sd_a**2 + sd_b**2) / delta**2


@dataclass(frozen=True)
class SeparationResult:
    """Episodes needed to tell `optimal` from a 5%-deviating player, by return and by regret."""

    episodes: int  # played by each player to measure the deviations
    delta: float  # the deviating player's mean exact regret per episode
    return_sd: tuple[float, float]  # optimal, deviating
    regret_sd: tuple[float, float]
    return_gap: float  # the difference of the measured mean returns

    @property
    def by_return(self) -> float:
        return episodes_needed(*self.return_sd, self.delta)

    @property
    def by_regret(self) -> float:
        return episodes_needed(*self.regret_sd, self.delta)

    @property
    def ratio(self) -> float:
        return self.by_return / self.by_regret


def measure_separation(episodes: int, seed: int = 0) -> SeparationResult:
    """Play `episodes` Blackjack episodes with each player and derive both counts."""
    best = run_benchmark("blackjack", OptimalPlayer(), episodes=episodes, seed=seed)
    worse = run_benchmark("blackjack", DeviatingPlayer(DEVIATION, seed), episodes=episodes,
                          seed=seed)
    assert best.regrets is not None and worse.regrets is not None
    return SeparationResult(
        episodes=episodes, delta=float(worse.regrets.mean() - best.regrets.mean()),
        return_sd=(float(best.returns.std(ddof=1)), float(worse.returns.std(ddof=1))),
        regret_sd=(float(best.regrets.std(ddof=1)), float(worse.regrets.std(ddof=1))),
        return_gap=float(best.returns.mean() - worse.returns.mean()),
    )


@dataclass(frozen=True)
class RateResult:
    """Steps per second, one figure per repeat (None: not measured, `reason` says why)."""

    samples: tuple[float, ...] = ()
    reason: str = ""

    @property
    def steps_per_second(self) -> float | None:
        return median(self.samples) if self.samples else None


@dataclass(frozen=True)
class RoundTripResult:
    """One request at a time: the round trip of a step (microseconds), and steps per second."""

    p50_us: float | None = None
    p95_us: float | None = None
    round_trips: int = 0
    rate: RateResult = RateResult()


class _ProtocolChild:
    """`tui-gym play gridworld --jsonl` as a child process, driven through its raw pipes."""

    def __init__(self) -> None:
        self.child = subprocess.Popen(
            [sys.executable, "-m", "tui_gym", "play", "gridworld", "--jsonl", "--size", "12"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0,
        )
        assert self.child.stdin is not None and self.child.stdout is not None
        self.requests, self.answers = self.child.stdin, self.child.stdout  # raw: no buffers
        self.sent = 0  # step requests written (their parity picks the action)
        self.tail = b""  # the start of an answer whose newline has not come yet

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[self.requests.write(view):]

    def send_steps(self, count: int) -> None:
        first = self.sent
        self.sent += count
        self.write(b"".join(STEP_LINES[k & 1] for k in range(first, first + count)))

    def read_answers(self) -> int:
        """Wait for answers; how many whole ones came. RuntimeError on an error answer."""
        data = self.answers.read(1 << 16)
        if not data:
            raise RuntimeError("the protocol process exited")
        data = self.tail + data
        end = data.rfind(b"\n") + 1
        whole, self.tail = data[:end], data[end:]
        if b'"error"' in whole:
            bad = next(line for line in whole.splitlines() if b'"error"' in line)
            raise RuntimeError(f"the protocol answered {bad.decode(errors='replace')}")
        return whole.count(b"\n")

    def reset(self) -> None:
        self.write(b'{"cmd":"reset","seed":1}\n')
        while not self.read_answers():
            pass

    def close(self) -> None:
        self.requests.close()  # end of input: the child answers what is left and exits
        self.answers.read()
        self.child.wait(timeout=30)


def _pipe_windows(seconds: float, repeats: int, window: int) -> tuple[list[float], list[float]]:
    """Protocol steps per second over a pipe with `window` requests in flight, `repeats`
    windows on one child process; and each answer's time since the last request went out
    (with one request in flight: each step's round trip)."""
    pipe = _ProtocolChild()
    rates: list[float] = []
    trips: list[float] = []
    try:
        pipe.reset()
        pipe.send_steps(window)
        for _ in range(repeats):
            answered, started = 0, time.perf_counter()
            sent = now = started
            while now < started + seconds:
                got = pipe.read_answers()
                now = time.perf_counter()
                if got:
                    trips.append(now - sent)
                    answered, sent = answered + got, now
                    pipe.send_steps(got)  # one new request per answer: the window stays full
            rates.append(answered / (now - started))
    finally:
        pipe.close()
    return rates, trips


def measure_protocol(seconds: float, repeats: int) -> RateResult:
    """Protocol steps per second over a pipe with `WINDOW` requests in flight."""
    return RateResult(tuple(_pipe_windows(seconds, repeats, WINDOW)[0]))


def measure_round_trip(seconds: float, repeats: int) -> RoundTripResult:
    """Protocol steps one at a time over a pipe: each step's round trip."""
    rates, trips = _pipe_windows(seconds, repeats, 1)
    return RoundTripResult(
        p50_us=percentile(trips, 50) * 1e6, p95_us=percentile(trips, 95) * 1e6,
        round_trips=len(trips), rate=RateResult(tuple(rates)),
    )


async def _mcp_steps(client: Any, game_id: int, until: float) -> int:
    steps = 0
    while time.perf_counter() < until:
        result = await client.call_tool(
            "step", {"game_id": game_id, "action": ("up", "down")[steps & 1]}
        )
        steps += 1
        if result.structured_content["done"]:
            await client.call_tool("reset", {"game_id": game_id})
    return steps


async def _mcp_windows(seconds: float, repeats: int) -> tuple[RateResult, RateResult]:
    import anyio
    from mcp import Client, StdioServerParameters

    params = StdioServerParameters(command=sys.executable, args=["-m", "tui_gym", "mcp"])
    rates: dict[int, list[float]] = {1: [], MCP_GAMES: []}  # by the games played at once
    async with Client(params) as client:
        games = []
        for k in range(MCP_GAMES):
            started = await client.call_tool(
                "start_game", {"game": "gridworld", "seed": k, "parameters": {"size": 12}}
            )
            games.append(started.structured_content["game_id"])  # type: ignore[index]
        for _ in range(repeats):
            for at_once, samples in rates.items():
                counts = [0] * at_once
                began = time.perf_counter()

                async def play(k: int, until: float, into: list[int]) -> None:
                    into[k] = await _mcp_steps(client, games[k], until)

                async with anyio.create_task_group() as group:
                    for k in range(at_once):
                        group.start_soon(play, k, began + seconds, counts)
                samples.append(sum(counts) / (time.perf_counter() - began))
    return RateResult(tuple(rates[1])), RateResult(tuple(rates[MCP_GAMES]))


def measure_mcp(seconds: float, repeats: int) -> tuple[RateResult, RateResult]:
    """MCP `step` calls per second through the SDK's client over stdio: one call at a
    time, and `MCP_GAMES` games played at once."""
    try:
        import anyio
        import mcp  # noqa: F401
    except ImportError:
        missing = RateResult(reason="not measured: the mcp extra is not installed "
                                    "(pip install 'tui-gym[mcp]')")
        return missing, missing
    return anyio.run(_mcp_windows, seconds, repeats)


@dataclass(frozen=True)
class ProgramsResult:
    """The figures of this module."""

    separation: SeparationResult
    protocol: RateResult  # `WINDOW` requests in flight
    mcp_one: RateResult  # one call at a time
    mcp_together: RateResult  # `MCP_GAMES` games at once
    protocol_round_trip: RoundTripResult = RoundTripResult()  # one request at a time


def measure(separation_episodes: int, seconds: float, repeats: int) -> ProgramsResult:
    """Every figure of this module (see its docstring)."""
    one, together = measure_mcp(seconds, repeats)
    return ProgramsResult(
        separation=measure_separation(separation_episodes),
        protocol=measure_protocol(seconds, repeats), mcp_one=one, mcp_together=together,
        protocol_round_trip=measure_round_trip(seconds, repeats),
    )
