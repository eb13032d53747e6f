"""Learning to a bound: the time until the greedy policy is within the target gap of the
optimum (ours and the tutorial loop's), and planning's worth, the real episodes Q-learning
and Dyna-Q take to a bound."""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tui_gym.algorithms import Settings
from tui_gym.bench import tutorial
from tui_gym.bench.figures import median
from tui_gym.core.mdp import NotAvailable
from tui_gym.games import Game
from tui_gym.session.session import (
    TARGET_GAP_BUDGET_FACTOR,
    Session,
    check_every_for,
    default_settings,
)


@dataclass(frozen=True)
class GapRun:
    """One run toward the target: its wall time, episodes and last checked gap."""

    seed: int
    seconds: float
    episodes: int
    gap: float
    reached: bool  # False: `seconds` is only a lower bound on the time to the target


@dataclass(frozen=True)
class GapResult:
    """Time to the target gap on one game, ours and the tutorial's (medians over seeds)."""

    target: float
    ours: tuple[GapRun, ...]
    tutorial: tuple[GapRun, ...]
    title: str = ""

    @property
    def time_to_gap_s(self) -> float:
        return median([r.seconds for r in self.ours])

    @property
    def tutorial_time_to_gap_s(self) -> float:
        return median([r.seconds for r in self.tutorial])

    @property
    def reached(self) -> bool:
        return all(r.reached for r in self.ours)

    @property
    def tutorial_reached(self) -> bool:
        return bool(self.tutorial) and all(r.reached for r in self.tutorial)

    @property
    def speedup(self) -> float | None:
        """Tutorial time / our time; a lower bound when `tutorial_reached` is False."""
        ours = self.time_to_gap_s
        if not self.ours or not self.tutorial or ours <= 0:
            return None
        return self.tutorial_time_to_gap_s / ours


def bench_kwargs(game: Game) -> dict[str, Any]:
    return game.normalize_kwargs(game.bench_kwargs or {})


def default_hyperparameters(game: Game) -> Settings:
    """The hyperparameters `tui-gym train GAME --target-gap G` uses (Q-learning's)."""
    hp = default_settings(game, "q-learning", bench_kwargs(game))
    return hp.replace(episodes=TARGET_GAP_BUDGET_FACTOR * hp.episodes)


def tutorial_runs(game: Game, seeds: Sequence[int], cap_seconds: float,
                  target: float) -> list[GapRun]:
    """The tutorial loop with the same hyperparameters and budget, capped in time."""
    hp = default_hyperparameters(game)
    tasks = [{"kind": "gap", "game": game.name, "kwargs": bench_kwargs(game), "hp": dict(hp),
              "target": target, "seed": seed, "cap": cap_seconds,
              "check_every": check_every_for(hp.episodes)} for seed in seeds]
    return [GapRun(seed, run["seconds"], run["episodes"], run["gap"], run["reached"])
            for seed, run in zip(seeds, tutorial.measure(tasks), strict=True)]


def measure_game(game: Game, seeds: Sequence[int], tutorial_seeds: int,
                 tutorial_cap_s: float) -> GapResult:
    """Ours on every seed, as the CLI runs `--target-gap`; the tutorial on the first
    `tutorial_seeds` of them, each run stopped at `tutorial_cap_s` (or at the budget)."""
    kwargs, target = bench_kwargs(game), game.bench_gap
    if target is None:
        bound = game.oracle.bound(kwargs, Session(game.env_id, kwargs).changes)
        if isinstance(bound, NotAvailable) or bound.figure != "gap":
            raise ValueError(f"{game.title} states no gap to train to")
        target = bound.limit
    ours = []
    for seed in seeds:
        start = time.perf_counter()
        session = Session(game.env_id, kwargs, hp=default_hyperparameters(game), seed=seed)
        outcome = session.train(target_gap=target)
        seconds = time.perf_counter() - start
        session.env.close()
        gap = float(outcome.gap) if outcome.gap is not None else float("nan")
        ours.append(GapRun(seed, seconds, session.trainer.episodes, gap,
                           bool(outcome.reached_target)))
    theirs = tutorial_runs(game, seeds[: max(1, tutorial_seeds)], tutorial_cap_s, target)
    return GapResult(target, tuple(ours), tuple(theirs), title_of(game))


def title_of(game: Game) -> str:
    kwargs = game.bench_kwargs or {}
    extra = " ".join(f"{v}" if k == "map" else f"{k}={v}" for k, v in kwargs.items())
    return f"{game.title} {extra}".strip()


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
    q_runs, dyna_runs = (tuple(episodes_to_bound(game, name, bound, s, hp) for s in seeds)
                         for name, hp in (("q-learning", {}),
                                          ("dyna-q", {"planning_steps": PLANNING_STEPS})))
    return PlanningResult(game, measure, bound, q_runs, dyna_runs)
