"""Time to a target gap: how long until the greedy policy is within the target of the optimum.

For every game of the registry with `bench_kwargs`, to its `bench_gap` (else
the bound its oracle states: for a model game, 1% of the optimum's magnitude,
beyond what no fixed policy found reaches).

Ours: exactly what `tui-gym train GAME --target-gap G` runs, a `Session` on
the default engine ("auto": the vector engine) with the game's default
hyperparameters and the CLI's budget for a target gap (five times the
default), `session.train(target_gap=...)` checking the exact gap as it does.

The tutorial: the tutorial-style loop (`tutorial.py`) with the same
hyperparameters and budget, checking its exact gap as often.

Both clocks start before the env is built and stop when the check that met
the target returns, so both include their gap checks. Ours runs once per
seed and the tutorial on seeds in turn while the stage has time; the figures
are medians over seeds. A tutorial run stopped by its time cap or the stage's
budget only gives a lower bound on its time, and the figure says so
(`tutorial_reached` false, speed-up ">= x").
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from tui_gym.algorithms import Settings
from tui_gym.bench import tutorial
from tui_gym.bench.figures import median
from tui_gym.core.mdp import NotAvailable
from tui_gym.games import GAMES, Game
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


def benched() -> list[Game]:
    """The games the bench measures, in the registry's order."""
    return [game for game in GAMES if game.bench_kwargs is not None]


def bench_kwargs(game: Game) -> dict[str, Any]:
    return game.normalize_kwargs(game.bench_kwargs or {})


def target_for(game: Game) -> float:
    """The gap the bench trains `game` to."""
    if game.bench_gap is not None:
        return game.bench_gap
    bound = game.oracle.bound(bench_kwargs(game), Session(game.env_id,
                                                          bench_kwargs(game)).changes)
    if isinstance(bound, NotAvailable) or bound.figure != "gap":
        raise ValueError(f"{game.title} states no gap to train to")
    return bound.limit


def default_hyperparameters(game: Game) -> Settings:
    """The hyperparameters `tui-gym train GAME --target-gap G` uses (Q-learning's)."""
    hp = default_settings(game, "q-learning", bench_kwargs(game))
    return hp.replace(episodes=TARGET_GAP_BUDGET_FACTOR * hp.episodes)


def ours_once(game: Game, seed: int, target: float) -> GapRun:
    """Our default engine, as the CLI runs it for `--target-gap`."""
    start = time.perf_counter()
    session = Session(game.env_id, bench_kwargs(game), hp=default_hyperparameters(game),
                      seed=seed)
    outcome = session.train(target_gap=target)
    seconds = time.perf_counter() - start
    episodes = session.trainer.episodes
    session.env.close()
    gap = float(outcome.gap) if outcome.gap is not None else float("nan")
    return GapRun(seed, seconds, episodes, gap, bool(outcome.reached_target))


def tutorial_once(game: Game, seed: int, cap_seconds: float | None, target: float) -> GapRun:
    """The tutorial loop with the same hyperparameters and budget, capped in time."""
    hp = default_hyperparameters(game)
    run = tutorial.time_to_gap(target, game, bench_kwargs(game), hp, seed, cap_seconds,
                               check_every=check_every_for(hp.episodes))
    return GapRun(seed, run.seconds, run.episodes, run.gap, run.reached)


def measure_game(
    game: Game, seeds: Sequence[int], tutorial_cap_s: float, tutorial_stage_s: float
) -> GapResult:
    """Ours on every seed; the tutorial on seeds in turn while the stage has time left.

    The tutorial always runs at least once; each of its runs stops at
    `tutorial_cap_s` (or at the budget), and no new run starts once the
    tutorial has used `tutorial_stage_s` in all (so the stage takes at most
    about `tutorial_stage_s + tutorial_cap_s`).
    """
    target = target_for(game)
    ours: list[GapRun] = []
    theirs: list[GapRun] = []
    used = 0.0
    for seed in seeds:
        ours.append(ours_once(game, seed, target))
        if theirs and used >= tutorial_stage_s:
            continue
        run = tutorial_once(game, seed, tutorial_cap_s, target)
        theirs.append(run)
        used += run.seconds
    return GapResult(target, tuple(ours), tuple(theirs), title_of(game))


def title_of(game: Game) -> str:
    kwargs = game.bench_kwargs or {}
    extra = " ".join(f"{v}" if k == "map" else f"{k}={v}" for k, v in kwargs.items())
    return f"{game.title} {extra}".strip()


def measure(
    seeds: Sequence[int], tutorial_cap_s: float, tutorial_stage_s: float
) -> dict[str, GapResult]:
    """`measure_game` for every game the bench measures, by game name."""
    return {game.name: measure_game(game, seeds, tutorial_cap_s, tutorial_stage_s)
            for game in benched()}
