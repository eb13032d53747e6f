"""`tui-gym bench`: the baseline learns, the report says every figure, the CLI takes the flags.

Fast checks only: nothing here measures time or asserts a speed (the bench
prints figures; it never asserts them).
"""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np
import pytest
from rich.console import Console

from tui_gym.bench import parts, tutorial
from tui_gym.bench.compiling import CompileResult
from tui_gym.bench.defaults import DefaultsResult
from tui_gym.bench.gap import GapResult, GapRun
from tui_gym.bench.live import KeySample, LiveRepeat, LiveResult
from tui_gym.bench.memory import MemoryResult
from tui_gym.bench.parts import PartResult
from tui_gym.bench.report import LESSON, MISS, PASS, UNDECIDED, notes, table, to_json, verdicts
from tui_gym.bench.run import BenchResults, MachineInfo
from tui_gym.bench.speed import Speed
from tui_gym.bench.startup import StartupResult
from tui_gym.cli import build_parser, commands
from tui_gym.cli.output import _clean
from tui_gym.session.session import Session
from tui_gym.ui import textual_internals as internals

REQUIRED_KEYS = ("quick", "seconds", "machine", "compile", "speed", "gap", "live", "memory",
                 "startup", "figures", "verdicts", "errors")


# --- the tutorial baseline ------------------------------------------------------


def test_the_tutorial_loop_learns_with_the_rule_uncompiled() -> None:
    session = Session("blackjack", hp={"episodes": 3_000}, seed=0, engine="env")
    untrained = session.reference().figures["gap"]  # ties everywhere: far from the optimum
    steps = tutorial.play(session, episodes=3_000)
    assert session.agent.episode == 3_000 and steps >= 3_000
    assert session.reference().figures["gap"] < untrained / 2


def test_the_tutorial_tasks_run_in_a_process_with_nothing_compiled() -> None:
    rate, gap, learners = tutorial.measure([
        {"kind": "rate", "game": "frozenlake", "algorithm": "sarsa", "hp": {"episodes": 10**9},
         "seconds": 0.2, "seed": 0},
        {"kind": "gap", "game": "blackjack", "kwargs": {}, "hp": {"episodes": 200},
         "target": 1e-9, "seed": 0, "cap": 60.0, "check_every": 100},
        {"kind": "learners", "game": "cliffwalking", "algorithms": ["q-learning"],
         "hp": {"episodes": 3}, "seeds": 2, "episodes": 3},
    ])
    assert rate["steps_per_second"] > 0 and rate["seconds"] >= 0.2
    assert gap["episodes"] == 200 and not gap["reached"] and gap["gap"] > 1e-9
    assert learners["seconds"] > 0


def test_the_tutorial_loop_goes_on_from_the_learner_the_engine_hands_over(
        monkeypatch, tmp_path) -> None:
    # The speed stage times both loops on a learner as far along: the tutorial's rate
    # task loads the learner the engine had when its window began.
    from tui_gym.bench import speed

    handed: list[object] = []

    def tutorial_runs(tasks: list[dict]) -> list[dict]:
        for task in tasks:
            session = tutorial._session(task["game"], task["algorithm"], task["hp"], 0)
            played = session.agent.episode
            monkeypatch.setattr(tutorial, "play", lambda s, **_: handed.append(
                (s.agent.episode, s.agent.q.copy())) or 1)
            tutorial._run(task)
            handed.append(played)
        return [{"steps_per_second": 1.0}] * len(tasks)

    monkeypatch.setattr(tutorial, "measure", tutorial_runs)
    (found,) = speed.measure(["gridworld"], ["q-learning"], 0.01, 1)
    (warm_episode, warm_q), (_, _), fresh = handed
    assert fresh == 0 and warm_episode > 0 and np.abs(warm_q).sum() > 0
    assert found.tutorial_steps == 1.0 and found.steps > 0


def test_the_tutorial_trains_to_the_gap_on_the_game_the_bench_names(monkeypatch) -> None:
    from tui_gym.bench import gap
    from tui_gym.games import game_for

    asked: list[dict] = []
    monkeypatch.setattr(tutorial, "measure", lambda tasks: asked.extend(tasks) or [
        {"seconds": 1.0, "episodes": 1, "gap": 0.0, "reached": True}])
    lake = game_for("frozenlake")
    gap.tutorial_runs(lake, [0], 1.0, 0.1)
    assert asked[0]["kwargs"] == gap.bench_kwargs(lake) and asked[0]["kwargs"]["map"] == "8x8"


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
        "thread", (LiveRepeat(1_600_000, 500_000, 14.0, 13.0, "model", _keys(100.0)),), 3.0
    )
    process = LiveResult(
        "process", (LiveRepeat(1_600_000, 1_550_000, 14.5, 14.0, "model", _keys(20.0)),), 3.0
    )
    if failed_live:
        thread = LiveResult("thread", (), 3.0, ("TimeoutError: timed out waiting for x",))
    return BenchResults(
        quick=True,
        seconds=55.0,
        machine=MachineInfo(2, (1.5, 1.0, 0.5), (1.2, 1.0, 0.5)),
        compile=CompileResult(24.0, 0.9, 0.4),
        speed=(Speed("blackjack", "sarsa", 2_000_000.0, 15_000.0, 1.5),
               Speed("blackjack", "dyna-q", 400_000.0, 5_000.0, 1.5)),
        gap={"blackjack": gap},
        defaults=(DefaultsResult("blackjack", "sarsa", "gap <= 0.005", 39, 40, 0.0061),
                  DefaultsResult("blackjack", "dyna-q", "gap <= 0.005", 36, 40, 0.009)),
        live={"thread": thread, "process": process},
        memory=MemoryResult(2_000_000, 100_000, "model", 40.0, 40.6, 40.7, 1.5),
        startup=StartupResult((0.8, 0.9, 0.85)),
        parts=(PartResult("compositor", 30.0, 61.0, 0.95),),
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
    figures = data["figures"]
    assert (figures["cold_compile_s"], figures["warm_load_s"]) == (24.0, 0.4)
    assert [figures[f"speedup[blackjack/{name}]"] for name in ("sarsa", "dyna-q")] == \
        pytest.approx([2_000_000 / 15_000, 80.0])
    assert (data["speed"][0]["steps"], data["speed"][0]["mean_length"]) == (2_000_000, 1.5)
    assert figures["defaults[blackjack/sarsa]"] == pytest.approx(39 / 40)
    assert data["verdicts"]["speedup[blackjack/sarsa]"] == PASS
    assert data["verdicts"]["speedup[blackjack/dyna-q]"] == MISS
    assert data["verdicts"]["defaults[blackjack/sarsa]"] == PASS
    assert data["verdicts"]["defaults[blackjack/dyna-q]"] == MISS
    assert data["verdicts"]["cold_compile_s"] == PASS == data["verdicts"]["warm_load_s"]
    assert figures["time_to_gap_s[blackjack]"] == pytest.approx(0.11)
    assert data["gap"]["blackjack"]["tutorial"][0]["reached"] is True
    assert figures["time_to_gap[blackjack]"] == pytest.approx(10.0 / 0.11)
    assert data["default_runner"] == "process"
    assert figures["live_ratio[process]"] == pytest.approx(1_550_000 / 1_600_000)
    assert set(data["live"]) == {"thread", "process"}
    assert figures["live_ratio[thread]"] == pytest.approx(500_000 / 1_600_000)
    assert figures["rss_growth_mb"] == pytest.approx(0.6)
    assert figures["startup_s"] == pytest.approx(0.85)
    assert data["verdicts"]["time_to_gap[blackjack]"] == PASS
    assert data["verdicts"]["live_ratio[thread]"] == MISS
    assert data["verdicts"]["key_latency_p95_ms[thread]"] == MISS
    assert data["verdicts"]["key_latency_p95_ms[process]"] == PASS


def test_a_lesson_is_the_verdict_only_of_a_pair_that_ends_short() -> None:
    """A pair its game names a lesson for reads "lesson" when its defaults end short of the
    bound, and PASS when they reach it like any other pair."""
    results = dataclasses.replace(fake_results(), defaults=(
        DefaultsResult("cliffwalking", "sarsa", "gap <= 0.13", 0, 8, 4.0, "why"),
        DefaultsResult("dyna-maze", "sarsa", "extra_steps <= 0", 8, 8, 0.0, "why")))
    found = to_json(results)["verdicts"]
    assert found["defaults[cliffwalking/sarsa]"] == LESSON
    assert found["defaults[dyna-maze/sarsa]"] == PASS


def test_the_table_shows_each_figure_its_target_and_verdict() -> None:
    text = rendered(fake_results())
    for words in ("tutorial loop", "blackjack, sarsa", "1,333,333", "time to gap", "≥ 50×",
                  "≥ 100×", "39 of 40", "every learner compiled", "24.0 s",
                  "thread runner", "process runner (default)", "≥ 0.80", "Hz", "p95",
                  "RSS growth", "start to first frame", "PASS", "MISS"):
        assert words in text, words


def test_each_speed_part_left_to_textual_is_shown_beside_ours() -> None:
    data = to_json(fake_results())
    assert data["figures"]["stock_key_p95_ms[compositor]"] == 61.0
    assert data["figures"]["stock_startup_s[compositor]"] == 0.95
    ours = data["figures"]["key_latency_p95_ms[process]"]
    text = rendered(fake_results())
    assert "Textual's own compositor" in text and f"61 ms (p50 30; ours {ours:.0f} ms)" in text
    assert "0.95 s (ours 0.85 s)" in text and "TUI_GYM_STOCK_TEXTUAL" in text


def test_a_part_is_left_to_textual_only_while_it_is_measured(monkeypatch) -> None:
    monkeypatch.delenv(internals.STOCK_ENV, raising=False)
    with parts.stock("compositor"):
        assert not internals.enabled("compositor") and internals.enabled("focus")
    assert internals.enabled("compositor") and internals.STOCK_ENV not in os.environ


def test_a_comparison_runner_that_misses_is_explained() -> None:
    text = rendered(fake_results())  # the default (process) passes, the thread runner misses
    assert "The app trains with the process runner" in text
    assert "process runner" not in " ".join(notes(fake_results(failed_live=True)))


def test_a_capped_tutorial_gives_a_lower_bound() -> None:
    decided = fake_results(tutorial_reached=False, tutorial_seconds=15.0)
    assert verdicts(decided)["time_to_gap[blackjack]"] == PASS  # >= 136x already beats 50x
    assert not any(run["reached"] for run in to_json(decided)["gap"]["blackjack"]["tutorial"])
    text = rendered(decided)
    assert "≥ 15.0 s (capped)" in text and "lower bounds" in text
    undecided = fake_results(tutorial_reached=False, tutorial_seconds=0.5)
    assert verdicts(undecided)["time_to_gap[blackjack]"] == UNDECIDED


def test_a_failed_stage_is_reported_not_raised() -> None:
    results = fake_results(failed_live=True)
    data = to_json(results)
    assert data["live"]["thread"]["errors"] == ("TimeoutError: timed out waiting for x",)
    assert data["verdicts"]["live_ratio[thread]"] == "n/a"
    assert data["figures"]["live_ratio[process]"] is not None  # the default runner measured
    assert "timed out waiting" in rendered(results)
    empty = BenchResults(quick=False, seconds=1.0, machine=MachineInfo(None, None, None),
                         errors={"speed": "RuntimeError: boom"})
    data = json.loads(json.dumps(_clean(to_json(empty))))
    for key in REQUIRED_KEYS:
        assert key in data, key
    assert data["gap"] == {} and data["errors"] == {"speed": "RuntimeError: boom"}
    assert "boom" in rendered(empty)


# --- the command line -------------------------------------------------------------
def test_the_parser_accepts_bench_quick_json() -> None:
    args = build_parser().parse_args(["bench", "--quick", "--json"])
    assert (args.command, args.quick, args.json) == ("bench", True, True)
    args = build_parser().parse_args(["bench"])
    assert (args.quick, args.json) == (False, False)
    assert callable(commands.cmd_bench)


# --- planning -----------------------------------------------------------------------


def test_the_planning_figure_has_a_target_and_a_verdict() -> None:
    from dataclasses import replace

    from tui_gym.bench.gap import PlanningResult, PlanningRun

    planning = PlanningResult(
        "gridworld", "share of pairs", 0.02,
        (PlanningRun("q-learning", 0, 3_000, True),),
        (PlanningRun("dyna-q", 0, 500, True),),
    )
    results = replace(fake_results(), planning=planning)
    assert verdicts(results)["planning"] == PASS
    assert to_json(results)["figures"]["planning"] == [3_000, 500]
    assert "3,000 / 500" in rendered(results)
