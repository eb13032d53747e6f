"""The bench's comparison figure: its verdict, row and JSON (nothing here is timed)."""

from __future__ import annotations

from dataclasses import replace

from rich.console import Console

from tui_gym.bench.compare import SeedsSpeed
from tui_gym.bench.report import MISS, PASS, table, to_json, verdicts
from tui_gym.bench.run import BenchResults, MachineInfo


def _results(compare_s: float) -> BenchResults:
    speed = SeedsSpeed("cliffwalking", ("q-learning", "sarsa"), 50, 500, compare_s, 300.0, 20,
                       (-55.0, -36.5))
    return BenchResults(quick=True, seconds=1.0, machine=MachineInfo(2, None, None),
                        seeds=speed)


def test_the_comparison_figure_has_a_target_a_row_and_json() -> None:
    fast, slow = _results(1.0), _results(4.0)
    assert verdicts(fast)["compare_speedup"] == PASS
    assert verdicts(slow)["compare_speedup"] == MISS
    assert verdicts(fast)["example_6_6"] == PASS
    data = to_json(fast)
    assert data["figures"]["compare_speedup"] == 300.0 and data["seeds"]["tutorial_learners"] == 20
    assert data["figures"]["example_6_6"] == [-55.0, -36.5]
    console = Console(record=True, width=160)
    console.print(table(fast))
    text = console.export_text()
    assert "compare on cliffwalking, 50 seeds × 500 ep" in text
    assert "300.0× (300.0 s, 20 of 100 run, scaled / 1.00 s)" in text and "≥ 100×" in text
    assert "-55.0 / -36.5" in text
    whole = replace(fast, seeds=replace(fast.seeds, tutorial_learners=100))
    console = Console(record=True, width=160)
    console.print(table(whole))
    assert "scaled" not in console.export_text()
