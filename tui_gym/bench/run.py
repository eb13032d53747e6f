"""One bench run: every stage in turn, with the sizes of the quick or the full plan.

`run_bench(quick, progress, algorithms)` measures throughput and time to
the target gap (on every game the bench measures), every algorithm's
vector-engine speed against its tutorial loop (or the named ones'), Dyna-Q's
planning against Q-learning, `compare` against the same learners one after
another, live training (both runners), memory, start-up, programs as players
(exact-regret scoring against returns, protocol and MCP speeds), and the run
history's cost (recording's share of a train run, the file's size per 1,000
runs), and returns `BenchResults`. A stage that fails is recorded in `errors`
and the others still run. `progress` (if given) hears the name of each stage
as it starts.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from tui_gym.algorithms import ALGORITHMS
from tui_gym.bench import (
    dp,
    gap,
    history,
    learners,
    live,
    map_edit,
    memory,
    programs,
    seeds,
    startup,
    throughput,
)
from tui_gym.bench.figures import load_average
from tui_gym.bench.results import BenchResults, MachineInfo


@dataclass(frozen=True)
class Plan:
    """How much of each measurement a run does."""

    throughput_seconds: float  # window per engine per repeat
    throughput_repeats: int
    gap_seeds: tuple[int, ...]  # ours runs every seed
    tutorial_cap_s: float  # one tutorial run stops here (a lower bound then)
    tutorial_stage_s: float  # no new tutorial run starts past this
    live_seconds: float  # the measuring window, headless and live
    live_repeats: int
    key_presses: int  # per repeat
    memory_episodes: int
    memory_warmup: int
    startup_repeats: int
    algorithm_seconds: float  # window per side per repeat, each (game, algorithm)
    algorithm_repeats: int
    planning_seeds: tuple[int, ...]
    separation_episodes: int = 5_000  # each of the two Blackjack players
    pipe_seconds: float = 1.0  # window per repeat, protocol and MCP
    pipe_repeats: int = 3
    compare_seeds: int = 50  # `compare`: seeds per algorithm, episodes per seed
    compare_episodes: int = 500
    compare_tutorial_share: float = 1.0  # of the learners the tutorial loop runs


# About 2 minutes on an idle 2-CPU machine; the tutorial gets one capped run a game.
QUICK = Plan(
    throughput_seconds=0.5, throughput_repeats=3,
    gap_seeds=(0, 1, 2), tutorial_cap_s=10.0, tutorial_stage_s=0.0,
    live_seconds=1.0, live_repeats=1, key_presses=30,
    memory_episodes=2_000_000, memory_warmup=100_000,
    startup_repeats=3,
    algorithm_seconds=0.3, algorithm_repeats=3, planning_seeds=(0,),
    compare_tutorial_share=0.1,
)
# About 12 minutes on an idle 2-CPU machine.
FULL = Plan(
    throughput_seconds=2.0, throughput_repeats=3,
    gap_seeds=(0, 1, 2), tutorial_cap_s=60.0, tutorial_stage_s=60.0,
    live_seconds=3.0, live_repeats=3, key_presses=30,
    memory_episodes=2_000_000, memory_warmup=100_000,
    startup_repeats=5,
    algorithm_seconds=1.0, algorithm_repeats=3, planning_seeds=(0, 1, 2),
    separation_episodes=20_000, pipe_seconds=2.0,
)


def run_bench(
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
    algorithms: tuple[str, ...] | None = None,
) -> BenchResults:
    """Measure everything (see the module docstring); `algorithms` (registry names)
    limits the per-algorithm speeds to those (default: every one)."""
    plan = QUICK if quick else FULL
    say = progress or (lambda _text: None)
    errors: dict[str, str] = {}
    found: dict[str, Any] = {}

    def stage(name: str, text: str, measure: Callable[[], Any]) -> None:
        say(text)
        try:
            found[name] = measure()
        except Exception as exc:  # one broken stage must not hide the others' figures
            errors[name] = f"{type(exc).__name__}: {exc}"

    started = time.perf_counter()
    load_before = load_average()
    rates: dict[str, throughput.ThroughputResult] = {}
    gaps: dict[str, gap.GapResult] = {}
    for index, game in enumerate(gap.benched()):
        name = game.name
        stage(f"throughput[{name}]", f"throughput on {gap.title_of(game)}: the tutorial loop "
              "and our engines",
              partial(throughput.measure_game, game, plan.throughput_seconds,
                      plan.throughput_repeats, scalar=index == 0))
        if f"throughput[{name}]" in found:
            rates[name] = found.pop(f"throughput[{name}]")
    cap = f"capped at {plan.tutorial_cap_s:.0f} s"
    for game in gap.benched():
        name = game.name
        stage(f"gap[{name}]", f"time to the target gap on {gap.title_of(game)}: ours, then the "
              f"tutorial loop ({cap})",
              partial(gap.measure_game, game, plan.gap_seeds, plan.tutorial_cap_s,
                      plan.tutorial_stage_s))
        if f"gap[{name}]" in found:
            gaps[name] = found.pop(f"gap[{name}]")
    names = algorithms or tuple(cls.name for cls in ALGORITHMS)
    stage("algorithms", f"each algorithm's vector engine against its tutorial loop "
          f"({', '.join(names)})",
          lambda: learners.measure_speed(names, plan.algorithm_seconds, plan.algorithm_repeats))
    stage("planning", f"real episodes to the bound: Q-learning, then Dyna-Q "
          f"(planning_steps = {learners.PLANNING_STEPS}) on {learners.PLANNING_GAME}",
          lambda: learners.measure_planning(plan.planning_seeds, learners.PLANNING_BOUND))
    stage("seeds", f"compare, {plan.compare_seeds} seeds × {plan.compare_episodes} episodes of "
          "Q-learning and SARSA, against the same learners in a tutorial loop",
          lambda: seeds.measure(plan.compare_seeds, plan.compare_episodes,
                                plan.compare_tutorial_share))
    stage("live", "live training in the app",
          lambda: live.measure(plan.live_seconds, plan.key_presses, plan.live_repeats,
                               progress=say))
    stage("memory", f"memory over {plan.memory_episodes:,} episodes",
          lambda: memory.measure(plan.memory_episodes, plan.memory_warmup))
    stage("startup", "start-up to the first frame",
          lambda: startup.measure(plan.startup_repeats))
    stage("programs", "programs as players: episodes to separate two players, protocol "
          "and MCP steps/s",
          lambda: programs.measure(plan.separation_episodes, plan.pipe_seconds,
                                   plan.pipe_repeats))
    stage("map_edit", f"map editor: an edit to the new optimum on {map_edit.MAP_SIDE}x"
          f"{map_edit.MAP_SIDE} maps", lambda: tuple(map_edit.measure()))
    stage("history", "the run history: recording's share of a train run, the file's size",
          lambda: history.measure(3 if quick else 5))
    stage("dp", "planning: sweeps, Jack's car rental, the Plan view",
          lambda: dp.measure(plan.live_seconds, plan.key_presses, plan.live_repeats, say))
    return BenchResults(
        quick=quick,
        seconds=time.perf_counter() - started,
        machine=MachineInfo(os.cpu_count(), load_before, load_average()),
        throughput=rates,
        gap=gaps,
        live=found.get("live", {}),
        memory=found.get("memory"),
        startup=found.get("startup"),
        algorithms=found.get("algorithms"),
        planning=found.get("planning"),
        programs=found.get("programs"),
        map_edit=found.get("map_edit"),
        history=found.get("history"),
        seeds=found.get("seeds"),
        dp=found.get("dp"),
        errors=errors,
    )
