"""Training throughput: episodes per second of the tutorial loop and of our engines, per game.

For every game the bench measures (`gap.benched`), each repeat trains a fresh
agent for a fixed wall-clock window, in turn: the tutorial-style loop
(`tutorial.py`) on the game's own Gymnasium env, our vector engine and, for
the first game, our scalar engine (`Trainer` on one Gymnasium env), all with
the game's default hyperparameters and a budget far beyond the window (so
epsilon stays near its start and every engine plays the same kind of
episodes). The engines are timed inside `trainer.run(seconds=...)`, after a
warm-up that finishes every game in progress at least once; the tutorial
after `gym.make`.

The vector engine starts thousands of episodes together, and where nearly
every episode runs to the time limit (a random walk on Taxi or CliffWalking)
they end together too: counting the episodes that happen to end inside a
short window would measure that window's luck. So an engine's episodes per
second are its steps per second over the window divided by the mean length
of its episodes (the tutorial loop's, played one after the other, are
counted as they end). Interleaving them within each
repeat spreads the machine's background load over all of them; each figure is
the median over the repeats, and the speed-ups are ratios of those medians.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from tui_gym.algorithms import Settings
from tui_gym.bench import tutorial
from tui_gym.bench.figures import median, ratio
from tui_gym.bench.gap import bench_kwargs, benched, title_of
from tui_gym.games import Game
from tui_gym.session.session import Session, default_settings

WINDOW_BUDGET = 1_000_000_000  # episodes: never reached in a window, so epsilon barely moves
WARMUP_SECONDS = 0.1


@dataclass(frozen=True)
class ThroughputResult:
    """Episodes per second on one game (medians over `repeats`); `scalar` None: not measured."""

    tutorial: float
    scalar: float | None
    vector: float
    repeats: int
    seconds: float  # the window of each measurement
    title: str = ""
    vector_steps: float = float("nan")  # steps per second of the vector engine

    @property
    def vector_speedup(self) -> float | None:
        return ratio(self.vector, self.tutorial)

    @property
    def scalar_speedup(self) -> float | None:
        return ratio(self.scalar, self.tutorial)


def window_settings(game: Game, kwargs: dict[str, Any]) -> Settings:
    """Q-learning's settings for the game, with a budget far beyond the window."""
    return default_settings(game, "q-learning", kwargs).replace(episodes=WINDOW_BUDGET)


def engine_rate(
    game: Game, engine: str, seconds: float, seed: int = 0
) -> tuple[float, float]:
    """Episodes and steps per second of a fresh session of `game` on `engine` ("scalar" or
    "vector"): steps over the window, and steps / the mean episode length."""
    kwargs = bench_kwargs(game)
    hp = window_settings(game, kwargs)
    session = Session(game.env_id, kwargs, hp=hp, seed=seed, engine=engine)
    trainer = session.trainer
    games_at_once = getattr(trainer, "num_envs", 1)
    warm = time.perf_counter()
    while trainer.episodes < games_at_once or time.perf_counter() - warm < WARMUP_SECONDS:
        trainer.run(seconds=WARMUP_SECONDS)
    steps = trainer.steps
    start = time.perf_counter()
    trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - start
    steps_per_second = (trainer.steps - steps) / elapsed
    length = trainer.windows["length"].mean
    session.env.close()
    return steps_per_second / max(length, 1.0), steps_per_second


def measure_game(game: Game, seconds: float, repeats: int, scalar: bool) -> ThroughputResult:
    """Interleaved repeats of the tutorial loop and our engines on one game; medians."""
    kwargs = bench_kwargs(game)
    hp = window_settings(game, kwargs)
    rates: dict[str, list[float]] = {"tutorial": [], "scalar": [], "vector": [], "steps": []}
    for seed in range(repeats):
        rates["tutorial"].append(tutorial.episodes_per_second(seconds, game, kwargs, hp, seed))
        if scalar:
            rates["scalar"].append(engine_rate(game, "scalar", seconds, seed)[0])
        episodes, steps = engine_rate(game, "vector", seconds, seed)
        rates["vector"].append(episodes)
        rates["steps"].append(steps)
    return ThroughputResult(
        tutorial=median(rates["tutorial"]),
        scalar=median(rates["scalar"]) if scalar else None,
        vector=median(rates["vector"]),
        repeats=repeats,
        seconds=seconds,
        title=title_of(game),
        vector_steps=median(rates["steps"]),
    )


def measure(seconds: float, repeats: int) -> dict[str, ThroughputResult]:
    """`measure_game` for every game the bench measures (the scalar engine on the first)."""
    games = benched()
    return {game.name: measure_game(game, seconds, repeats, scalar=i == 0)
            for i, game in enumerate(games)}
