"""One bench run: every stage in turn, with the sizes of the quick or the full plan, and what
it found (`BenchResults`)."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from tui_gym.algorithms import ALGORITHMS, Predictor, algorithm
from tui_gym.bench import (
    compare,
    compiling,
    defaults,
    dp,
    gap,
    history,
    live,
    map_edit,
    memory,
    parts,
    programs,
    speed,
    startup,
)
from tui_gym.bench.compare import SeedsSpeed, TasksResult
from tui_gym.bench.compiling import CompileResult
from tui_gym.bench.defaults import DefaultsResult
from tui_gym.bench.dp import DPResult
from tui_gym.bench.figures import load_average
from tui_gym.bench.gap import GapResult, PlanningResult
from tui_gym.bench.history import HistoryResult
from tui_gym.bench.live import DEFAULT_RUNNER, LiveResult
from tui_gym.bench.map_edit import MapEditResult
from tui_gym.bench.memory import MemoryResult
from tui_gym.bench.parts import PartResult
from tui_gym.bench.programs import ProgramsResult
from tui_gym.bench.speed import Speed
from tui_gym.bench.startup import StartupResult
from tui_gym.games import GAMES


@dataclass(frozen=True)
class MachineInfo:
    """The machine the figures were measured on, and how busy it was."""

    cpus: int | None
    load_before: tuple[float, float, float] | None
    load_after: tuple[float, float, float] | None


@dataclass(frozen=True)
class BenchResults:
    """Every stage's result (None when it failed: `errors` says why)."""

    quick: bool
    seconds: float  # the whole run
    machine: MachineInfo
    compile: CompileResult | None = None
    speed: tuple[Speed, ...] | None = None  # every (game, algorithm) against the tutorial
    gap: dict[str, GapResult] = field(default_factory=dict)  # by game name
    live: dict[str, LiveResult] = field(default_factory=dict)  # by runner
    memory: MemoryResult | None = None
    startup: StartupResult | None = None
    parts: tuple[PartResult, ...] | None = None  # the app with each speed part left to Textual
    planning: PlanningResult | None = None  # Dyna-Q against Q-learning, real episodes
    programs: ProgramsResult | None = None
    map_edit: tuple[MapEditResult, ...] | None = None  # edit to new optimum, per grid game
    history: HistoryResult | None = None  # the run history's overhead and size
    seeds: SeedsSpeed | None = None  # `compare` against the same learners in a loop
    defaults: tuple[DefaultsResult, ...] | None = None  # the share of seeds at the bound
    dp: DPResult | None = None  # planning: sweeps, Jack's car rental, the Plan view
    tasks: TasksResult | None = None  # the task split's overhead, a Dask cluster's share
    errors: dict[str, str] = field(default_factory=dict)  # stage -> what went wrong
    default_runner: str = DEFAULT_RUNNER

    def live_for(self, runner: str) -> LiveResult | None:
        """A runner's live figures, or None when it has none (not run, or failed)."""
        result = self.live.get(runner)
        return result if result is not None and result.repeats else None


@dataclass(frozen=True)
class Plan:
    """How much of each measurement a run does."""

    speed_seconds: float  # window per side per repeat, each (game, algorithm)
    speed_repeats: int
    gap_seeds: tuple[int, ...]  # ours runs every seed
    tutorial_gap_seeds: int  # the tutorial the first ones
    tutorial_cap_s: float  # one tutorial run stops here (a lower bound then)
    live_seconds: float  # the measuring window, headless and live
    live_repeats: int
    key_presses: int  # per repeat
    memory_episodes: int
    memory_warmup: int
    startup_repeats: int
    planning_seeds: tuple[int, ...]
    defaults_seeds: int
    separation_episodes: int = 5_000  # each of the two Blackjack players
    pipe_seconds: float = 1.0  # window per repeat, protocol and MCP
    pipe_repeats: int = 3
    compare_seeds: int = 50  # `compare`: seeds per algorithm, episodes per seed
    compare_episodes: int = 500
    compare_tutorial_share: float = 1.0  # of the learners the tutorial loop runs
    tasks_scale: int = 20  # the task split is timed on `compare_episodes` × this many (spread)


# About 5 minutes on an idle 2-CPU machine.
QUICK = Plan(
    speed_seconds=0.3, speed_repeats=1, gap_seeds=(0, 1, 2), tutorial_gap_seeds=1,
    tutorial_cap_s=10.0, live_seconds=1.0, live_repeats=1, key_presses=30,
    memory_episodes=2_000_000, memory_warmup=100_000, startup_repeats=3,
    planning_seeds=(0,), defaults_seeds=8, compare_tutorial_share=0.1,
)
# About 20 minutes on an idle 2-CPU machine.
FULL = Plan(
    speed_seconds=1.0, speed_repeats=3, gap_seeds=(0, 1, 2), tutorial_gap_seeds=3,
    tutorial_cap_s=60.0, live_seconds=3.0, live_repeats=3, key_presses=30,
    memory_episodes=2_000_000, memory_warmup=100_000, startup_repeats=5,
    planning_seeds=(0, 1, 2), defaults_seeds=defaults.SEEDS, separation_episodes=20_000,
    pipe_seconds=2.0,
)


def run_bench(
    quick: bool = False, progress: Callable[[str], None] | None = None,
    algorithms: tuple[str, ...] | None = None,
) -> BenchResults:
    """Measure everything (see the module docstring); `algorithms` (registry names)
    limits the per-algorithm figures to those (default: every one)."""
    plan = QUICK if quick else FULL
    say = progress or (lambda _text: None)
    errors: dict[str, str] = {}
    found: dict[str, Any] = {}

    def stage(name: str, text: str, measure: Callable[[], Any], into: dict[str, Any] = found,
              key: str = "") -> None:
        say(text)
        try:
            into[key or name] = measure()
        except Exception as exc:  # one broken stage must not hide the others' figures
            errors[name] = f"{type(exc).__name__}: {exc}"

    started = time.perf_counter()
    load_before = load_average()
    games = [game.name for game in GAMES]  # speed and defaults: every game
    names = algorithms or tuple(cls.name for cls in ALGORITHMS)
    stage("compile", "compiling every learner with an empty cache, then loading it",
          compiling.measure)
    stage("speed", f"training speed of {', '.join(names)} on every game: ours, and the "
          "tutorial loop", lambda: speed.measure(games, names, plan.speed_seconds,
                                                 plan.speed_repeats))
    gaps: dict[str, GapResult] = {}
    for game in [g for g in GAMES if g.bench_kwargs is not None]:  # the games the bench times
        stage(f"gap[{game.name}]", f"time to the target gap on {gap.title_of(game)}: ours, "
              f"then the tutorial loop (capped at {plan.tutorial_cap_s:.0f} s)",
              partial(gap.measure_game, game, plan.gap_seeds, plan.tutorial_gap_seeds,
                      plan.tutorial_cap_s), gaps, game.name)
    stage("planning", f"real episodes to the bound: Q-learning, then Dyna-Q "
          f"(planning_steps = {gap.PLANNING_STEPS}) on {gap.PLANNING_GAME}",
          lambda: gap.measure_planning(plan.planning_seeds, gap.PLANNING_BOUND))
    stage("seeds", f"compare, {plan.compare_seeds} seeds × {plan.compare_episodes} episodes of "
          "Q-learning and SARSA, against the same learners in a tutorial loop",
          lambda: compare.measure_seeds(plan.compare_seeds, plan.compare_episodes,
                                plan.compare_tutorial_share))
    stage("tasks", f"compare in tasks against one batch, {plan.compare_seeds} seeds; a sweep "
          f"on LocalCluster({compare.CLUSTER_WORKERS}) against the local executor",
          lambda: compare.measure_tasks(plan.compare_seeds,
                                        plan.compare_episodes * plan.tasks_scale,
                                        1 if quick else 3))
    control = tuple(n for n in names if not issubclass(algorithm(n), Predictor))  # bounds
    stage("defaults", f"the defaults over {plan.defaults_seeds} seeds: the share that reaches "
          "the bound", lambda: defaults.measure(games, control, plan.defaults_seeds))
    stage("live", "live training in the app",
          lambda: live.measure(plan.live_seconds, plan.key_presses, plan.live_repeats,
                               progress=say))
    stage("memory", f"memory over {plan.memory_episodes:,} episodes",
          lambda: memory.measure(plan.memory_episodes, plan.memory_warmup))
    stage("startup", "start-up to the first frame", lambda: startup.measure(plan.startup_repeats))
    stage("parts", "key latency and start-up with each speed part of Textual's private names "
          "left to Textual", lambda: parts.measure(plan.live_seconds, plan.key_presses,
                                                   plan.live_repeats, plan.startup_repeats, say))
    stage("programs", "programs as players: episodes to separate two players, protocol "
          "and MCP steps/s",
          lambda: programs.measure(plan.separation_episodes, plan.pipe_seconds, plan.pipe_repeats))
    stage("map_edit", f"map editor: an edit to the new optimum on {map_edit.MAP_SIDE}x"
          f"{map_edit.MAP_SIDE} maps", lambda: tuple(map_edit.measure()))
    stage("history", "the run history: recording's share of a train run, the file's size",
          lambda: history.measure(3 if quick else 5))
    stage("dp", "planning: sweeps, Jack's car rental, the Plan view",
          lambda: dp.measure(plan.live_seconds, plan.key_presses, plan.live_repeats, say))
    return BenchResults(quick=quick, seconds=time.perf_counter() - started,
                        machine=MachineInfo(os.cpu_count(), load_before, load_average()),
                        gap=gaps, errors=errors, **found)
