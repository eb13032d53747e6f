"""Time to a target gap: how long until the greedy policy is within 0.002 of the optimum.

Ours: exactly what `tui-gym train blackjack --target-gap 0.002` runs, a
`Session` on the default engine ("auto": the vector engine for Blackjack)
with the default hyperparameters and the CLI's budget for a target gap
(`TARGET_GAP_BUDGET`, 1,000,000 episodes), `session.train(target_gap=...)`
checking the exact gap every 10,000 episodes.

The tutorial: the tutorial-style loop (`tutorial.py`) with the same
hyperparameters and budget, checking its exact gap every 10,000 episodes too.

Both clocks start before the env is built and stop when the check that met
the target returns, so both include their gap checks. Each side runs once per
seed, and the figures are medians over seeds. The tutorial can take long, so
each of its runs has a time cap and the stage stops adding seeds past a time
budget; a run stopped by the cap or the budget only gives a lower bound on its
time, and then the figure says so (`tutorial_reached` false, speed-up ">= x").
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from tui_gym.bench import tutorial
from tui_gym.bench.figures import median
from tui_gym.core.agent import Hyperparameters
from tui_gym.core.session import TARGET_GAP_BUDGET, Session
from tui_gym.games import game_for

TARGET_GAP = 0.002
ENV_ID = "Blackjack-v1"


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
    """Time to the target gap, ours and the tutorial's (medians over seeds)."""

    target: float
    ours: tuple[GapRun, ...]
    tutorial: tuple[GapRun, ...]

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


def default_hyperparameters() -> Hyperparameters:
    """The hyperparameters `tui-gym train blackjack --target-gap G` uses."""
    return game_for(ENV_ID).default_hyperparameters().replace(episodes=TARGET_GAP_BUDGET)


def ours_once(seed: int, target: float = TARGET_GAP) -> GapRun:
    """Our default engine, as the CLI runs it for `--target-gap`."""
    start = time.perf_counter()
    session = Session(ENV_ID, hp=default_hyperparameters(), seed=seed)
    outcome = session.train(target_gap=target)
    seconds = time.perf_counter() - start
    episodes = session.trainer.episodes
    session.env.close()
    gap = float(outcome.gap) if outcome.gap is not None else float("nan")
    return GapRun(seed, seconds, episodes, gap, bool(outcome.reached_target))


def tutorial_once(seed: int, cap_seconds: float | None, target: float = TARGET_GAP) -> GapRun:
    """The tutorial loop with the same hyperparameters and budget, capped in time."""
    run = tutorial.time_to_gap(target, default_hyperparameters(), seed, cap_seconds)
    return GapRun(seed, run.seconds, run.episodes, run.gap, run.reached)


def measure(
    seeds: Sequence[int], tutorial_cap_s: float, tutorial_stage_s: float,
    target: float = TARGET_GAP,
) -> GapResult:
    """Ours on every seed; the tutorial on seeds in turn while the stage has time left.

    The tutorial always runs at least once; each of its runs stops at
    `tutorial_cap_s` (or at the budget), and no new run starts once the
    tutorial has used `tutorial_stage_s` in all (so the stage takes at most
    about `tutorial_stage_s + tutorial_cap_s`).
    """
    ours: list[GapRun] = []
    theirs: list[GapRun] = []
    used = 0.0
    for seed in seeds:
        ours.append(ours_once(seed, target))
        if theirs and used >= tutorial_stage_s:
            continue
        run = tutorial_once(seed, tutorial_cap_s, target)
        theirs.append(run)
        used += run.seconds
    return GapResult(target, tuple(ours), tuple(theirs))
