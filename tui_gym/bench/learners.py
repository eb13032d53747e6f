"""Figures per algorithm: vector-engine speed against a tutorial loop, and planning's worth.

`measure_speed`: for each (game, algorithm), the episodes per second of our
vector engine and of a tutorial-style loop of the same algorithm
(`tutorial_learners`) on the same Gymnasium env, with the algorithm's
defaults for the game and a budget far beyond the window (so epsilon stays at
its start and both sides play the same kind of episodes). Each repeat times
the two in turn; the figures are medians over the repeats and the speed-up is
their ratio.

`measure_planning`: how many real episodes Q-learning and Dyna-Q (with
`planning_steps` = 10) take to bring the exact gap of their greedy policy
within a bound on a grid game, on the vector engine with a few envs side by
side (so the count of real episodes is fine-grained), checked every few
episodes; the median over seeds of each.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from tui_gym.bench import tutorial_learners
from tui_gym.bench.figures import median, ratio
from tui_gym.session.session import Session

SPEED_BUDGET = 1_000_000_000  # episodes: never reached in a window, so epsilon stays put
SPEED_WARMUP_S = 0.1
SPEED_GAMES = ("blackjack", "gridworld")
PLANNING_GAME = "gridworld"
PLANNING_STEPS = 10
PLANNING_ENVS = 8  # games side by side while counting episodes to the bound
PLANNING_CHECK = 16  # episodes between checks of the exact gap
PLANNING_BUDGET = 20_000
PLANNING_BOUND = 0.02


@dataclass(frozen=True)
class AlgorithmSpeed:
    """Episodes per second of one algorithm on one game: ours and the tutorial loop's."""

    game: str
    algorithm: str
    vector: float
    tutorial: float
    repeats: int

    @property
    def speedup(self) -> float | None:
        return ratio(self.vector, self.tutorial)


@dataclass(frozen=True)
class PlanningRun:
    """Real episodes one learner took to reach the bound (budget: not reached)."""

    algorithm: str
    seed: int
    episodes: int
    reached: bool


@dataclass(frozen=True)
class PlanningResult:
    """Q-learning against Dyna-Q: real episodes to a bound on the exact gap."""

    game: str
    measure: str  # what the bound is on, in words
    bound: float
    q_learning: tuple[PlanningRun, ...]
    dyna_q: tuple[PlanningRun, ...]

    @property
    def q_learning_episodes(self) -> float:
        return median([r.episodes for r in self.q_learning])

    @property
    def dyna_q_episodes(self) -> float:
        return median([r.episodes for r in self.dyna_q])

    @property
    def reached(self) -> bool:
        return all(r.reached for r in (*self.q_learning, *self.dyna_q))


def _vector_rate(game: str, algorithm: str, seconds: float, seed: int) -> float:
    session = Session(game, seed=seed, algorithm=algorithm, engine="vector",
                      hp={"episodes": SPEED_BUDGET})
    trainer = session.trainer
    trainer.run(seconds=SPEED_WARMUP_S)
    start = time.perf_counter()
    done = trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - start
    session.env.close()
    return done / elapsed


def _tutorial_rate(game: str, algorithm: str, seconds: float, seed: int) -> float:
    session = Session(game, seed=seed, algorithm=algorithm, hp={"episodes": SPEED_BUDGET})
    env_id, kwargs, hp = session.env_id, dict(session.env_kwargs), session.hp
    session.env.close()
    assert hp is not None
    return tutorial_learners.episodes_per_second(env_id, kwargs, algorithm, hp, seconds, seed)


def measure_speed(
    algorithms: Sequence[str], seconds: float, repeats: int,
    games: Sequence[str] = SPEED_GAMES,
) -> tuple[AlgorithmSpeed, ...]:
    """Interleaved repeats of the tutorial loop and our vector engine; medians."""
    out = []
    for game in games:
        for algorithm in algorithms:
            ours, theirs = [], []
            for seed in range(repeats):
                theirs.append(_tutorial_rate(game, algorithm, seconds, seed))
                ours.append(_vector_rate(game, algorithm, seconds, seed))
            out.append(AlgorithmSpeed(game, algorithm, median(ours), median(theirs), repeats))
    return tuple(out)


def _distance(session: Session) -> tuple[str, float]:
    """What the bound is on, and its value now: the exact gap, or for games scored by
    shortest paths the share of states whose greedy path is not a shortest one."""
    reference = session.reference()
    assert reference is not None
    figures = reference.figures
    if "gap" in figures:
        return "exact gap to the optimum", figures["gap"]
    return "share of (agent, target) pairs not solved in the fewest steps", (
        1.0 - figures["optimal_pair_fraction"]
    )


def episodes_to_bound(
    game: str, algorithm: str, bound: float, seed: int, overrides: dict | None = None
) -> PlanningRun:
    """Real episodes until the bound is met (checked every `PLANNING_CHECK`)."""
    hp = {"episodes": PLANNING_BUDGET, **(overrides or {})}
    session = Session(game, seed=seed, algorithm=algorithm, engine="vector", hp=hp)
    trainer = session.vector_trainer(seed=seed, num_envs=PLANNING_ENVS)
    try:
        while trainer.remaining:
            trainer.run(episodes=min(PLANNING_CHECK, trainer.remaining))
            if _distance(session)[1] <= bound:
                return PlanningRun(algorithm, seed, trainer.episodes, True)
        return PlanningRun(algorithm, seed, trainer.episodes, False)
    finally:
        session.env.close()


def measure_planning(seeds: Sequence[int], bound: float = PLANNING_BOUND,
                     game: str = PLANNING_GAME) -> PlanningResult:
    """Q-learning and Dyna-Q (planning_steps = 10) on `game`, each seed in turn."""
    probe = Session(game, seed=0)
    measure = _distance(probe)[0]
    probe.env.close()
    q_runs = tuple(episodes_to_bound(game, "q-learning", bound, s) for s in seeds)
    dyna_runs = tuple(
        episodes_to_bound(game, "dyna-q", bound, s, {"planning_steps": PLANNING_STEPS})
        for s in seeds
    )
    return PlanningResult(game, measure, bound, q_runs, dyna_runs)
