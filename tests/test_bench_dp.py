"""Planning's bench figures: each row beside its target and verdict, in the table and the
JSON (fast checks: nothing here measures a speed)."""

from __future__ import annotations

import dataclasses

from rich.console import Console

from tests.test_bench import fake_results
from tui_gym.bench.dp import DPResult, ViewFigures
from tui_gym.bench.report import MISS, MISSING, PASS, table, to_json, verdicts


def results_with(dp: DPResult | None):
    return dataclasses.replace(fake_results(), dp=dp)


def test_the_planning_rows_have_targets_and_verdicts() -> None:
    dp = DPResult(0.4, 0.35, 0.6, (ViewFigures("gridworld", 31.0, (12.0, 20.0, 30.0)),
                                   ViewFigures("frozenlake", 12.0, (40.0, 90.0))))
    found = verdicts(results_with(dp))
    assert found["taxi_sweep_ms"] == PASS and found["jack_policy_iteration_s"] == PASS
    assert found["plan_sweeps_per_second[gridworld]"] == PASS
    assert found["plan_key_p95_ms[gridworld]"] == PASS
    assert found["plan_sweeps_per_second[frozenlake]"] == MISS
    assert found["plan_key_p95_ms[frozenlake]"] == MISS
    data = to_json(results_with(dp))
    assert data["figures"]["taxi_sweep_ms"] == 0.4 and len(data["dp"]["views"][0]["keys_ms"]) == 3
    console = Console(record=True, width=160)
    console.print(table(results_with(dp)))
    text = console.export_text()
    for words in ("value-iteration sweep on Taxi", "≤ 5 ms", "Jack's car rental", "≤ 1 s",
                  "Plan view on gridworld", "≥ 20", "≤ 50 ms"):
        assert words in text, words


def test_a_missing_planning_stage_is_said() -> None:
    assert verdicts(results_with(None))["plan_view"] == MISSING
