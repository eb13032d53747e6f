"""Training throughput: episodes per second of the tutorial loop and of our two engines.

Each repeat trains a fresh agent for a fixed wall-clock window, in turn: the
tutorial-style loop (`tutorial.py`), our scalar engine (`Trainer` on one
Gymnasium env) and our vector engine (`VectorTrainer`), all on Blackjack with
the default hyperparameters and a budget far beyond the window (so epsilon
stays near its start and every engine plays the same kind of hands). The
engines are timed inside `trainer.run(seconds=...)`, after a short warm-up;
the tutorial after `gym.make`. Interleaving the three within each repeat
spreads the machine's background load over all of them; each figure is the
median over the repeats, and the speed-ups are ratios of those medians.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from tui_gym.algorithms import QLearning
from tui_gym.bench import tutorial
from tui_gym.bench.figures import median, ratio
from tui_gym.core.session import Session

WINDOW_BUDGET = 1_000_000_000  # episodes: never reached in a window, so epsilon barely moves
WARMUP_SECONDS = 0.1


@dataclass(frozen=True)
class ThroughputResult:
    """Episodes per second (medians over `repeats`)."""

    tutorial: float
    scalar: float
    vector: float
    repeats: int
    seconds: float  # the window of each measurement

    @property
    def vector_speedup(self) -> float | None:
        return ratio(self.vector, self.tutorial)

    @property
    def scalar_speedup(self) -> float | None:
        return ratio(self.scalar, self.tutorial)


def engine_rate(engine: str, seconds: float, seed: int = 0) -> float:
    """Episodes per second of a fresh Blackjack session on `engine` ("scalar" or "vector")."""
    hp = QLearning.hyperparameters(episodes=WINDOW_BUDGET)
    session = Session("Blackjack-v1", hp=hp, seed=seed, engine=engine)
    trainer = session.trainer
    trainer.run(seconds=WARMUP_SECONDS)
    start = time.perf_counter()
    done = trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - start
    session.env.close()
    return done / elapsed


def measure(seconds: float, repeats: int) -> ThroughputResult:
    """Interleaved repeats of the tutorial loop and both engines; medians."""
    hp = QLearning.hyperparameters(episodes=WINDOW_BUDGET)
    rates: dict[str, list[float]] = {"tutorial": [], "scalar": [], "vector": []}
    for seed in range(repeats):
        rates["tutorial"].append(tutorial.episodes_per_second(seconds, hp, seed=seed))
        rates["scalar"].append(engine_rate("scalar", seconds, seed))
        rates["vector"].append(engine_rate("vector", seconds, seed))
    return ThroughputResult(
        tutorial=median(rates["tutorial"]),
        scalar=median(rates["scalar"]),
        vector=median(rates["vector"]),
        repeats=repeats,
        seconds=seconds,
    )
