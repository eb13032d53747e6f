"""Training speed per game and algorithm: ours against the tutorial loop of the same algorithm."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from tui_gym.bench import tutorial
from tui_gym.bench.figures import median, ratio
from tui_gym.session.session import Session

WINDOW_BUDGET = 1_000_000_000  # episodes: never reached in a window, so epsilon barely moves
WARMUP_SECONDS = 0.2


@dataclass(frozen=True)
class Speed:
    """Steps and episodes per second of one algorithm on one game, ours and the tutorial's."""

    game: str
    algorithm: str
    steps: float
    tutorial_steps: float
    mean_length: float  # of the engine's episodes in the window

    @property
    def episodes(self) -> float:
        return self.steps / max(self.mean_length, 1.0)

    @property
    def tutorial_episodes(self) -> float:
        return self.tutorial_steps / max(self.mean_length, 1.0)

    @property
    def speedup(self) -> float | None:
        return ratio(self.steps, self.tutorial_steps)


def engine_rate(game: str, algorithm: str, seconds: float, seed: int) -> tuple[float, float]:
    """Steps per second of the engine, and the mean length of its episodes."""
    session = Session(game, algorithm=algorithm, hp={"episodes": WINDOW_BUDGET}, seed=seed)
    trainer = session.trainer
    trainer.run(seconds=WARMUP_SECONDS)
    steps, episodes, began = trainer.steps, trainer.episodes, time.perf_counter()
    trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - began
    played = max(trainer.episodes - episodes, 1)
    session.env.close()
    return (trainer.steps - steps) / elapsed, (trainer.steps - steps) / played


def measure(games: Sequence[str], algorithms: Sequence[str], seconds: float,
            repeats: int) -> tuple[Speed, ...]:
    """Every (game, algorithm): the tutorial loop's repeats in one process, then ours."""
    tasks = [{"kind": "rate", "game": game, "algorithm": algorithm, "seed": seed,
              "hp": {"episodes": WINDOW_BUDGET}, "seconds": seconds}
             for game in games for algorithm in algorithms for seed in range(repeats)]
    theirs = iter(tutorial.measure(tasks))
    out = []
    for game in games:
        for algorithm in algorithms:
            tutorial_steps = median([next(theirs)["steps_per_second"] for _ in range(repeats)])
            ours = [engine_rate(game, algorithm, seconds, seed) for seed in range(repeats)]
            out.append(Speed(game, algorithm, median([s for s, _ in ours]), tutorial_steps,
                             median([length for _, length in ours])))
    return tuple(out)
