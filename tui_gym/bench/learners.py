"""Planning's worth: real episodes to a bound, Q-learning against Dyna-Q."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from tui_gym.bench.figures import median
from tui_gym.session.session import Session

PLANNING_GAME = "gridworld"
PLANNING_STEPS = 10
PLANNING_CHECK = 16  # episodes between checks of the exact gap
PLANNING_BUDGET = 20_000
PLANNING_BOUND = 0.02


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
    session = Session(game, seed=seed, algorithm=algorithm, hp=hp)
    trainer = session.trainer
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
