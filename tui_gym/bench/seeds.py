"""The comparison figure: `compare` against the same learners one after another, in the loop."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from tui_gym.bench import tutorial
from tui_gym.bench.figures import median, ratio

GAME = "cliffwalking"
ALGORITHMS = ("q-learning", "sarsa")
SETTINGS = {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5,
            "learning_rate_schedule": "constant"}
COMPARE_REPEATS = 3  # the comparison is short, so its time is the median of a few runs


@dataclass(frozen=True)
class SeedsSpeed:
    """`compare` against the tutorial loop on the same learners (seconds each), and the
    comparison's mean online return per algorithm over all its episodes."""

    game: str
    algorithms: tuple[str, ...]
    seeds: int
    episodes: int
    compare_s: float
    tutorial_s: float  # all the learners (scaled up from `tutorial_learners` of them)
    tutorial_learners: int  # learners the tutorial loop actually ran
    online_returns: tuple[float, ...] = ()

    @property
    def speedup(self) -> float | None:
        return ratio(self.tutorial_s, self.compare_s)

    @property
    def learners(self) -> int:
        return self.seeds * len(self.algorithms)


def measure(seeds: int, episodes: int, tutorial_share: float = 1.0) -> SeedsSpeed:
    """Time the comparison, then the tutorial loop (see the module docstring)."""
    from tui_gym.session.experiments.compare import CompareSpec, run_compare

    spec = CompareSpec(GAME, ALGORITHMS, seeds, episodes, settings=SETTINGS)
    run_compare(CompareSpec(GAME, ALGORITHMS, 1, 1, settings=SETTINGS))  # compiled, once
    times, result = [], None
    for _ in range(COMPARE_REPEATS):
        started = time.perf_counter()
        result = run_compare(spec)
        times.append(time.perf_counter() - started)
    assert result is not None
    online = tuple(float(o.curve.mean.mean()) for o in result.outcomes)
    per_algorithm = max(1, min(seeds, math.ceil(seeds * tutorial_share)))
    (run,) = tutorial.measure([{"kind": "learners", "game": GAME, "algorithms": ALGORITHMS,
                                "hp": {**SETTINGS, "episodes": episodes},
                                "seeds": per_algorithm, "episodes": episodes}])
    return SeedsSpeed(
        game=GAME, algorithms=ALGORITHMS, seeds=seeds, episodes=episodes,
        compare_s=median(times), tutorial_s=run["seconds"] * seeds / per_algorithm,
        tutorial_learners=per_algorithm * len(ALGORITHMS), online_returns=online,
    )
