"""The bench's figures on programs as players: the episodes-to-separate formula, a
deviating player that deviates, and the report's rows (no speed is asserted)."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest
from rich.console import Console

from tests.test_bench import fake_results
from tui_gym.bench import programs
from tui_gym.bench.programs import (
    ProgramsResult,
    RateResult,
    SeparationResult,
    episodes_needed,
    measure_separation,
)
from tui_gym.bench.report import MISS, PASS, table, to_json, verdicts
from tui_gym.bench.run import BenchResults


def test_episodes_needed_is_the_two_sample_formula() -> None:
    assert episodes_needed(1.0, 1.0, 0.1) == pytest.approx(1.96**2 * 2 / 0.01)
    assert episodes_needed(0.0, 0.2, 0.04) == pytest.approx(1.96**2 * 0.04 / 0.0016)
    assert math.isinf(episodes_needed(1.0, 1.0, 0.0))


def test_a_five_percent_deviation_costs_regret_and_regret_needs_fewer_episodes() -> None:
    found = measure_separation(400, seed=2)
    assert found.regret_sd[0] == 0.0  # the optimal player never loses a thing
    assert found.delta > 0 and found.regret_sd[1] > 0
    assert 0.8 < found.return_sd[0] < 1.1  # a hand's return: about ±1
    assert found.by_regret < found.by_return and found.ratio == pytest.approx(
        found.by_return / found.by_regret
    )


def _with(found: ProgramsResult) -> BenchResults:
    return dataclasses.replace(fake_results(), programs=found)


SEPARATION = SeparationResult(20_000, 0.038, (0.953, 0.953), (0.0, 0.2), 0.04)


def test_the_report_shows_the_rows_and_judges_them() -> None:
    found = ProgramsResult(SEPARATION, RateResult((21_000.0, 22_000.0, 20_500.0)),
                           RateResult((900.0,)), RateResult((1_400.0,)))
    results = _with(found)
    verdict = verdicts(results)
    assert verdict["regret_separation_ratio"] == PASS
    assert verdict["protocol_steps_per_second"] == PASS
    assert verdict["mcp_steps_per_second"] == PASS
    data = json.loads(json.dumps(to_json(results)))["figures"]
    assert data["episodes_to_separate_by_regret"] == pytest.approx(SEPARATION.by_regret)
    assert data["protocol_steps_per_second"] == 21_000.0
    assert data["mcp_steps_per_second_one_call_at_a_time"] == 900.0
    console = Console(record=True, width=160)
    console.print(table(results))
    text = console.export_text()
    assert "by exact regret" in text and "protocol over a pipe" in text
    assert f"{programs.MCP_GAMES} games at once" in text


def test_without_the_mcp_extra_the_report_says_so() -> None:
    missing = RateResult(reason="not measured: the mcp extra is not installed")
    found = ProgramsResult(SEPARATION, RateResult((15_000.0,)), missing, missing)
    results = _with(found)
    assert verdicts(results)["protocol_steps_per_second"] == MISS
    assert verdicts(results)["mcp_steps_per_second"] == "n/a"
    console = Console(record=True, width=200)
    console.print(table(results))
    assert "the mcp extra is not installed" in console.export_text()
