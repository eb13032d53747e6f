"""The comparison figure: `compare` against the same learners one after another.

`measure(seeds, episodes, tutorial_share)` times `run_compare` (the median
of `COMPARE_REPEATS` runs) on the first game of `GAMES` the registry has:
Q-learning and SARSA, `seeds` seeds each, `episodes` episodes each, Sutton &
Barto's Example 6.6 settings (epsilon 0.1 throughout, step size 0.5), seeds
batched and the batches spread over every core (the calling thread plays
one, child processes the others, their start included). Then it times the
same learners, algorithm by algorithm and seed by seed, in a tutorial-style
loop (`tutorial_learners`) on the Gymnasium env the game is played on, with
the same settings. With `tutorial_share` below 1 only that share of each
algorithm's seeds run the loop, and its time is scaled up to all of them
(the learners are alike, so each takes about as long).
The speed-up is the ratio of the two times.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from tui_gym.bench.figures import median, ratio
from tui_gym.bench.tutorial_learners import TutorialLearner

GAMES = ("cliffwalking", "gridworld")  # the first the registry has is measured
ALGORITHMS = ("q-learning", "sarsa")
SETTINGS = {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5}
COMPARE_REPEATS = 3  # the comparison is short, so its time is the median of a few runs


@dataclass(frozen=True)
class SeedsSpeed:
    """`compare` against the tutorial loop on the same learners (seconds each)."""

    game: str
    algorithms: tuple[str, ...]
    seeds: int
    episodes: int
    compare_s: float
    tutorial_s: float  # all the learners (scaled up from `tutorial_learners` of them)
    tutorial_learners: int  # learners the tutorial loop actually ran
    processes: int

    @property
    def speedup(self) -> float | None:
        return ratio(self.tutorial_s, self.compare_s)

    @property
    def learners(self) -> int:
        return self.seeds * len(self.algorithms)


def pick_game() -> str:
    """The first of `GAMES` the registry plays."""
    from tui_gym.session.session import Session

    for name in GAMES:
        try:
            Session(env_id=name, engine="scalar").env.close()
        except ValueError:
            continue
        return name
    raise ValueError(f"none of {', '.join(GAMES)} is a game here")


def measure(seeds: int, episodes: int, tutorial_share: float = 1.0) -> SeedsSpeed:
    """Time the comparison, then the tutorial loop (see the module docstring)."""
    from tui_gym.session.experiments.compare import CompareSpec, _cores, run_compare
    from tui_gym.session.session import Session

    game = pick_game()
    spec = CompareSpec(game, ALGORITHMS, seeds, episodes, settings=SETTINGS)
    compare_times = []
    for _ in range(COMPARE_REPEATS):
        started = time.perf_counter()
        run_compare(spec)
        compare_times.append(time.perf_counter() - started)
    compare_s = median(compare_times)

    per_algorithm = max(1, min(seeds, math.ceil(seeds * tutorial_share)))
    tutorial_s = 0.0
    for name in ALGORITHMS:
        session = Session(env_id=game, engine="scalar", algorithm=name,
                          hp={**SETTINGS, "episodes": episodes})
        hp = session.learner_class.settings(session.hp)
        for seed in range(per_algorithm):
            env = session.make_env()
            env.reset(seed=seed)
            learner = TutorialLearner(env, name, hp, seed)
            started = time.perf_counter()
            for _ in range(episodes):
                learner.train_episode()
            tutorial_s += time.perf_counter() - started
            env.close()
        session.env.close()
    return SeedsSpeed(
        game=game, algorithms=ALGORITHMS, seeds=seeds, episodes=episodes,
        compare_s=compare_s, tutorial_s=tutorial_s * seeds / per_algorithm,
        tutorial_learners=per_algorithm * len(ALGORITHMS), processes=_cores(),
    )
