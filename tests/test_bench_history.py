"""The bench's run-history figures: the file size measurement, and how the report shows them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from rich.console import Console

from tui_gym.bench.history import HistoryResult, _size
from tui_gym.bench.report import MISS, PASS, table, to_json, verdicts
from tui_gym.bench.run import BenchResults, MachineInfo
from tui_gym.cli.output import _clean
from tui_gym.core.experiments import Curve, Figure, RunHistory, RunKind, RunSpec, RunStatus


def results(history: HistoryResult | None) -> BenchResults:
    return BenchResults(quick=True, seconds=1.0, machine=MachineInfo(2, None, None),
                        history=history)


def test_the_size_is_that_of_a_file_holding_that_many_copies(tmp_path: Path) -> None:
    template = tmp_path / "one.db"
    with RunHistory(template) as history:
        run = history.start_run(RunSpec(RunKind.TRAIN, "blackjack", "q-learning", seeds=(0,)))
        episodes = np.arange(1, 101) * 2000
        history.update(run, curves=[Curve("return", episodes, np.linspace(-0.4, -0.05, 100))],
                       figures=[Figure("mean_return_last", -0.07, "return")],
                       status=RunStatus.FINISHED)
    target = tmp_path / "many.db"
    size = _size(target, template, 20)
    assert size == target.stat().st_size
    with RunHistory(target) as history:
        runs = history.list_runs()
        assert sorted(r.seeds[0] for r in runs) == list(range(20))
        assert len(history.get_run(runs[0].id).curve("return")) == 100


def test_the_report_shows_the_figures_with_targets_and_verdicts() -> None:
    good = HistoryResult("blackjack", (0.004, 0.006, 0.005), (1.2, 1.1, 1.3), (1.1, 1.2, 1.1),
                         1000, 600_000)
    data = json.loads(json.dumps(_clean(to_json(results(good)))))
    assert data["figures"]["history_overhead"] == 0.005
    assert data["figures"]["history_mb_per_1000_runs"] == 0.6
    assert data["verdicts"]["history_overhead"] == PASS
    assert data["verdicts"]["history_mb_per_1000_runs"] == PASS
    console = Console(record=True, width=160)
    console.print(table(results(good)))
    text = console.export_text()
    assert "0.50% (median of 3)" in text and "≤ 2%" in text and "0.600 MB" in text

    heavy = HistoryResult("blackjack", (0.03,), (1.0,), (1.0,), 500, 600_000)
    assert verdicts(results(heavy))["history_overhead"] == MISS
    assert verdicts(results(heavy))["history_mb_per_1000_runs"] == MISS  # 1.2 MB per 1,000
    assert verdicts(results(None))["history_overhead"] == "n/a"
