"""Training speed per game and algorithm: ours against the tutorial loop of the same algorithm,
both training the same learner from the same point."""

from __future__ import annotations

import pickle
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tui_gym.bench import tutorial
from tui_gym.bench.figures import median
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


def engine_rate(game: str, algorithm: str, seconds: float, seed: int,
                handover: str | None = None) -> tuple[float, float]:
    """Steps per second of the engine, and the mean length of its episodes; the learner as
    the window begins is pickled to the file `handover`, for the tutorial loop to go on from."""
    session = Session(game, algorithm=algorithm, hp={"episodes": WINDOW_BUDGET}, seed=seed)
    trainer = session.trainer
    trainer.run(seconds=WARMUP_SECONDS)
    if handover is not None:
        with open(handover, "wb") as file:
            pickle.dump(trainer.agent.state(), file)
    steps, episodes, began = trainer.steps, trainer.episodes, time.perf_counter()
    trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - began
    played = max(trainer.episodes - episodes, 1)
    session.env.close()
    return (trainer.steps - steps) / elapsed, (trainer.steps - steps) / played


def measure(games: Sequence[str], algorithms: Sequence[str], seconds: float,
            repeats: int) -> tuple[Speed, ...]:
    """Every (game, algorithm): ours, then the tutorial loop's repeats in one process, each
    going on from the learner ours had when its window began (so both time a learner as far
    along: a model as full to plan over, as many predecessors to sweep)."""
    pairs = [(game, algorithm) for game in games for algorithm in algorithms]
    with tempfile.TemporaryDirectory(prefix="tui-gym-speed-") as folder:
        ours: list[tuple[float, float]] = []
        tasks: list[dict[str, Any]] = []
        for game, algorithm in pairs:
            for seed in range(repeats):
                handover = f"{folder}/{len(tasks)}.pickle"
                ours.append(engine_rate(game, algorithm, seconds, seed, handover))
                tasks.append({"kind": "rate", "game": game, "algorithm": algorithm,
                              "seed": seed, "hp": {"episodes": WINDOW_BUDGET},
                              "seconds": seconds, "learner": handover})
        theirs = [run["steps_per_second"] for run in tutorial.measure(tasks)]
    out = []
    for i, (game, algorithm) in enumerate(pairs):
        mine = ours[i * repeats:(i + 1) * repeats]
        out.append(Speed(game, algorithm, median([s for s, _ in mine]),
                         median(theirs[i * repeats:(i + 1) * repeats]),
                         median([length for _, length in mine])))
    return tuple(out)
