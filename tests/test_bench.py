"""`tui-gym bench`: the baseline learns, the report says every figure, the CLI takes the flags.

Fast checks only: nothing here measures time or asserts a speed (the bench
prints figures; it never asserts them).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from rich.console import Console

from tui_gym.algorithms import QLearning
from tui_gym.bench import tutorial
from tui_gym.bench.gap import GapResult, GapRun
from tui_gym.bench.live import KeySample, LiveRepeat, LiveResult
from tui_gym.bench.memory import MemoryResult
from tui_gym.bench.report import MISS, PASS, UNDECIDED, notes, table, to_json, verdicts
from tui_gym.bench.results import BenchResults, MachineInfo
from tui_gym.bench.startup import StartupResult
from tui_gym.bench.throughput import ThroughputResult
from tui_gym.cli import build_parser
from tui_gym.cli.commands import COMMANDS
from tui_gym.cli.output import _clean
from tui_gym.games import game_for
from tui_gym.games.blackjack.solver import DECISION_MASK, optimal_policy

REQUIRED_KEYS = (
    "tutorial_episodes_per_second",
    "engine_episodes_per_second",
    "time_to_gap_s",
    "tutorial_time_to_gap_s",
    "live_ratio",
    "ui_refresh_hz",
    "key_latency_p95_ms",
    "rss_growth_mb",
    "startup_s",
)


# --- the tutorial baseline ------------------------------------------------------
BLACKJACK = game_for("blackjack")


def test_the_tutorial_loop_learns() -> None:
    agent = tutorial.make_agent(BLACKJACK, {}, QLearning.hyperparameters(episodes=10_000), seed=0)
    untrained = agent.gap()  # sticks everywhere: about 0.14 below the optimum
    tutorial.train_episodes(agent, 10_000)
    trained = agent.gap()
    assert agent.episode == 10_000
    assert agent.epsilon == pytest.approx(QLearning.hyperparameters(episodes=10_000).epsilon_final)
    # 10,000 episodes bring it to about 0.015-0.03 (seeds 0-5); half the start is a wide margin.
    assert 0 <= trained < untrained / 2


def test_the_tutorial_gap_is_exact_for_the_optimal_policy() -> None:
    agent = tutorial.make_agent(BLACKJACK, {}, QLearning.hyperparameters(), seed=0)
    best = optimal_policy()
    for player, dealer, usable in zip(*np.nonzero(DECISION_MASK), strict=True):
        values = np.zeros(2)
        values[best[player, dealer, usable]] = 1.0
        agent.q_values[(int(player), int(dealer), int(usable))] = values
    assert agent.gap() == pytest.approx(0.0, abs=1e-12)


def test_a_capped_tutorial_run_says_it_did_not_reach_the_target() -> None:
    hp = QLearning.hyperparameters(episodes=2_000)
    run = tutorial.time_to_gap(1e-9, BLACKJACK, {}, hp, seed=0, check_every=1_000)
    assert not run.reached
    assert run.episodes == 2_000
    assert run.gap > 1e-9


# --- the report -----------------------------------------------------------------
def _keys(total: float) -> tuple[KeySample, ...]:
    return tuple(
        KeySample("p" if i % 2 else "t", total + i, 1.0, 2.0, total + i - 3.0) for i in range(30)
    )


def fake_results(
    tutorial_reached: bool = True, tutorial_seconds: float = 10.0, failed_live: bool = False
) -> BenchResults:
    gap = GapResult(
        target=0.002,
        ours=(GapRun(0, 0.1, 120_000, 0.0015, True), GapRun(1, 0.12, 130_000, 0.0018, True)),
        tutorial=(GapRun(0, tutorial_seconds, 150_000, 0.0016 if tutorial_reached else 0.004,
                         tutorial_reached),),
        title="Blackjack",
    )
    thread = LiveResult(
        "thread", (LiveRepeat(1_600_000, 500_000, 14.0, 13.0, "vector", _keys(100.0)),), 3.0
    )
    process = LiveResult(
        "process", (LiveRepeat(1_600_000, 1_550_000, 14.5, 14.0, "vector", _keys(20.0)),), 3.0
    )
    if failed_live:
        thread = LiveResult("thread", (), 3.0, ("TimeoutError: timed out waiting for x",))
    return BenchResults(
        quick=True,
        seconds=55.0,
        machine=MachineInfo(2, (1.5, 1.0, 0.5), (1.2, 1.0, 0.5)),
        throughput={"blackjack": ThroughputResult(15_000.0, 12_000.0, 1_500_000.0, 3, 0.5,
                                                  "Blackjack")},
        gap={"blackjack": gap},
        live={"thread": thread, "process": process},
        memory=MemoryResult(2_000_000, 100_000, "vector", 40.0, 40.6, 40.7, 1.5),
        startup=StartupResult((0.8, 0.9, 0.85)),
    )


def rendered(results: BenchResults) -> str:
    console = Console(record=True, width=140)
    console.print(table(results))
    for line in notes(results):
        console.print(line)
    return console.export_text()


def test_the_json_has_every_required_figure() -> None:
    data = json.loads(json.dumps(_clean(to_json(fake_results()))))
    for key in REQUIRED_KEYS:
        assert key in data, key
    assert set(data["engine_episodes_per_second"]) == {"scalar", "vector"}
    assert data["engine_episodes_per_second"]["vector"] == 1_500_000.0
    assert data["time_to_gap_s"] == pytest.approx(0.11)
    assert data["tutorial_reached"] is True
    assert data["time_to_gap_speedup"] == pytest.approx(10.0 / 0.11)
    assert data["default_runner"] == "process"
    assert data["live_ratio"] == pytest.approx(1_550_000 / 1_600_000)  # the default runner's
    assert set(data["runners"]) == {"thread", "process"}
    assert data["runners"]["thread"]["live_ratio"] == pytest.approx(500_000 / 1_600_000)
    assert data["rss_growth_mb"] == pytest.approx(0.6)
    assert data["startup_s"] == pytest.approx(0.85)
    assert data["verdicts"]["time_to_gap[blackjack]"] == PASS
    assert data["verdicts"]["live_ratio[thread]"] == MISS
    assert data["verdicts"]["key_latency_p95_ms[thread]"] == MISS
    assert data["verdicts"]["key_latency_p95_ms[process]"] == PASS


def test_the_table_shows_each_figure_its_target_and_verdict() -> None:
    text = rendered(fake_results())
    for words in ("tutorial loop", "vector engine", "1,500,000", "time to gap", "≥ 20×",
                  "thread runner", "process runner (default)", "≥ 0.80", "Hz", "p95",
                  "RSS growth", "start to first frame", "PASS", "MISS"):
        assert words in text, words


def test_a_comparison_runner_that_misses_is_explained() -> None:
    text = rendered(fake_results())  # the default (process) passes, the thread runner misses
    assert "The app trains with the process runner" in text
    assert "process runner" not in " ".join(notes(fake_results(failed_live=True)))


def test_a_capped_tutorial_gives_a_lower_bound() -> None:
    decided = fake_results(tutorial_reached=False, tutorial_seconds=15.0)
    assert verdicts(decided)["time_to_gap[blackjack]"] == PASS  # >= 136x already beats 8x
    assert to_json(decided)["time_to_gap_speedup_is_lower_bound"] is True
    text = rendered(decided)
    assert "≥ 15.0 s (capped)" in text and "lower bounds" in text
    undecided = fake_results(tutorial_reached=False, tutorial_seconds=0.5)
    assert verdicts(undecided)["time_to_gap[blackjack]"] == UNDECIDED


def test_a_failed_stage_is_reported_not_raised() -> None:
    results = fake_results(failed_live=True)
    data = to_json(results)
    assert data["runners"]["thread"] == {"error": "TimeoutError: timed out waiting for x"}
    assert data["verdicts"]["live_ratio[thread]"] == "n/a"
    assert data["live_ratio"] is not None  # the default (process) runner still measured
    assert "timed out waiting" in rendered(results)
    empty = BenchResults(quick=False, seconds=1.0, machine=MachineInfo(None, None, None),
                         errors={"throughput": "RuntimeError: boom"})
    data = json.loads(json.dumps(_clean(to_json(empty))))
    for key in REQUIRED_KEYS:
        assert key in data, key
    assert data["time_to_gap_s"] is None and data["errors"] == {"throughput": "RuntimeError: boom"}
    assert "boom" in rendered(empty)


# --- the command line -------------------------------------------------------------
def test_the_parser_accepts_bench_quick_json() -> None:
    args = build_parser().parse_args(["bench", "--quick", "--json"])
    assert (args.command, args.quick, args.json) == ("bench", True, True)
    args = build_parser().parse_args(["bench"])
    assert (args.quick, args.json) == (False, False)
    assert "bench" in COMMANDS


# --- per-algorithm figures ----------------------------------------------------------


def test_every_algorithm_has_a_tutorial_loop_that_learns() -> None:
    import gymnasium as gym

    from tui_gym.algorithms import ALGORITHMS
    from tui_gym.bench.tutorial_learners import TutorialLearner

    for cls in ALGORITHMS:
        env = gym.make("Blackjack-v1")
        env.reset(seed=0)
        hp = cls.settings({"episodes": 200})
        learner = TutorialLearner(env, cls.name, hp, seed=0)
        for _ in range(200):
            learner.train_episode()
        assert learner.episode == 200 and learner.epsilon == hp.epsilon_final
        assert any(v.any() for v in learner.q.values()), cls.name  # it updated its table
        env.close()


def test_the_algorithm_figures_have_targets_and_verdicts() -> None:
    from dataclasses import replace

    from tui_gym.bench.learners import AlgorithmSpeed, PlanningResult, PlanningRun

    speeds = (AlgorithmSpeed("blackjack", "sarsa", 1_000_000.0, 10_000.0, 3),
              AlgorithmSpeed("gridworld", "dyna-q", 8_000.0, 200.0, 3))
    planning = PlanningResult(
        "gridworld", "share of pairs", 0.02,
        (PlanningRun("q-learning", 0, 3_000, True),),
        (PlanningRun("dyna-q", 0, 500, True),),
    )
    results = replace(fake_results(), algorithms=speeds, planning=planning)
    verdict = verdicts(results)
    assert verdict["algorithm_speedup[blackjack/sarsa]"] == PASS
    assert verdict["algorithm_speedup[gridworld/dyna-q]"] == MISS  # 40x
    assert verdict["planning"] == PASS
    data = to_json(results)
    assert data["algorithms"][0]["speedup"] == pytest.approx(100.0)
    assert (data["planning"]["q_learning_episodes"], data["planning"]["dyna_q_episodes"]) == (
        3_000, 500)
    text = rendered(results)
    assert "sarsa on blackjack" in text and "3,000 / 500" in text and "≥ 50×" in text
