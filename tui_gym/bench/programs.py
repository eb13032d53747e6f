"""Programs as players: how many episodes exact-regret scoring needs, and protocol speeds.

**Episodes for a 95% separation.** The built-in `optimal` player and one that
deviates on 5% of Blackjack decisions (`DeviatingPlayer`: with probability
0.05 it takes an action that is not optimal) each play the same fixed-seed
benchmark. From the measured per-episode standard deviations of each score
(the return, and the exact regret) and the gap between the two players'
means, the episodes each player needs before the difference of the means is
1.96 standard errors wide is

    n = z^2 * (sd_a^2 + sd_b^2) / delta^2,    z = 1.96,

for two independent samples of n episodes. The gap `delta` is the same for
both scores in expectation (a player's expected regret per episode is its
expected return's gap to the optimum's), so the two counts differ by their
variances alone; both use the measured regret gap, the better-measured of the two.

**Protocol speed over a pipe.** `tui-gym play gridworld --jsonl` runs as a
child process; this process sends one step at a time and waits for each
answer before the next (as a player must), resetting when an episode ends.
Steps per second over a window, median over repeats.

**MCP speed.** `tui-gym mcp` runs as a child process and the MCP SDK's own
client calls `step` on GridWorld games: one call at a time on one game, and
`MCP_GAMES` games played at once (calls in flight together, as a program
evaluating several episodes would make them); measured only where the `mcp`
extra is installed.
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.bench.figures import median
from tui_gym.benchmark.players import InProcessPlayer, OptimalPlayer
from tui_gym.benchmark.referee import Referee
from tui_gym.benchmark.run import run_benchmark

Z95 = 1.96
DEVIATION = 0.05
MCP_GAMES = 4  # games one client plays at once for the MCP throughput
STEP_LINES = (b'{"cmd":"step","action":"up"}\n', b'{"cmd":"step","action":"down"}\n')


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
        episodes=episodes,
        delta=float(worse.regrets.mean() - best.regrets.mean()),
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


def measure_protocol(seconds: float, repeats: int) -> RateResult:
    """Protocol steps per second over a pipe: `repeats` windows on one child process."""
    child = subprocess.Popen(
        [sys.executable, "-m", "tui_gym", "play", "gridworld", "--jsonl", "--size", "12"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE,
    )
    assert child.stdin is not None and child.stdout is not None
    send, answer = child.stdin, child.stdout
    samples = []
    try:
        send.write(b'{"cmd":"reset","seed":1}\n')
        send.flush()
        answer.readline()
        for _ in range(repeats):
            steps = 0
            started = time.perf_counter()
            deadline = started + seconds
            while steps % 256 or time.perf_counter() < deadline:
                send.write(STEP_LINES[steps & 1])
                send.flush()
                line = answer.readline()
                steps += 1
                if b'"terminated": true' in line or b'"truncated": true' in line:
                    send.write(b'{"cmd":"reset"}\n')
                    send.flush()
                    answer.readline()
            samples.append(steps / (time.perf_counter() - started))
    finally:
        send.close()
        child.wait(timeout=30)
    return RateResult(tuple(samples))


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
    one: list[float] = []
    together: list[float] = []
    async with Client(params) as client:
        games = []
        for k in range(MCP_GAMES):
            started = await client.call_tool(
                "start_game", {"game": "gridworld", "seed": k, "parameters": {"size": 12}}
            )
            games.append(started.structured_content["game_id"])  # type: ignore[index]
        for _ in range(repeats):
            started_at = time.perf_counter()
            steps = await _mcp_steps(client, games[0], started_at + seconds)
            one.append(steps / (time.perf_counter() - started_at))
            counts = [0] * MCP_GAMES
            started_at = time.perf_counter()

            async def play(k: int, until: float, into: list[int]) -> None:
                into[k] = await _mcp_steps(client, games[k], until)

            async with anyio.create_task_group() as group:
                for k in range(MCP_GAMES):
                    group.start_soon(play, k, started_at + seconds, counts)
            together.append(sum(counts) / (time.perf_counter() - started_at))
    return RateResult(tuple(one)), RateResult(tuple(together))


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
    protocol: RateResult
    mcp_one: RateResult  # one call at a time
    mcp_together: RateResult  # `MCP_GAMES` games at once


def measure(separation_episodes: int, seconds: float, repeats: int) -> ProgramsResult:
    """Every figure of this module (see its docstring)."""
    one, together = measure_mcp(seconds, repeats)
    return ProgramsResult(
        separation=measure_separation(separation_episodes),
        protocol=measure_protocol(seconds, repeats),
        mcp_one=one,
        mcp_together=together,
    )
