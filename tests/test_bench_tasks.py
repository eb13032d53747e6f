"""The bench's task figures: the split's overhead and a Dask cluster's share, as the report
shows them."""

from __future__ import annotations

import json

from rich.console import Console

from tui_gym.bench.compare import TasksResult
from tui_gym.bench.report import MISS, PASS, table, to_json, verdicts
from tui_gym.bench.run import BenchResults, MachineInfo
from tui_gym.cli.output import _clean


def results(found: TasksResult | None) -> BenchResults:
    return BenchResults(quick=True, seconds=1.0, machine=MachineInfo(2, None, None),
                        tasks=found)


def test_the_report_shows_the_ratios_with_targets_and_verdicts() -> None:
    good = TasksResult("cliffwalking", 50, 500, tasks_s=1.05, batch_s=1.0, tasks=4,
                       local_s=2.0, cluster_s=2.2, cluster_tasks=8)
    data = json.loads(json.dumps(_clean(to_json(results(good)))))
    assert data["figures"]["task_split_overhead"] == 1.05 and data["tasks"]["tasks"] == 4
    assert abs(data["figures"]["cluster_throughput_share"] - 2.0 / 2.2) < 1e-12
    assert data["verdicts"]["task_split_overhead"] == PASS
    assert data["verdicts"]["cluster_throughput_share"] == PASS
    console = Console(record=True, width=160)
    console.print(table(results(good)))
    text = console.export_text()
    assert "1.050 (1.05 s / 1.00 s)" in text and "≤ 1.1" in text and "≥ 0.8" in text

    slow = TasksResult("cliffwalking", 50, 500, tasks_s=1.2, batch_s=1.0, tasks=4,
                       local_s=1.0, cluster_s=2.0)
    assert verdicts(results(slow))["task_split_overhead"] == MISS
    assert verdicts(results(slow))["cluster_throughput_share"] == MISS
    no_dask = TasksResult("cliffwalking", 50, 500, 1.0, 1.0, 4, cluster_note="no Dask")
    assert verdicts(results(no_dask))["cluster_throughput_share"] == "n/a"
    console.print(table(results(no_dask)))
    assert "no Dask" in console.export_text()
    assert verdicts(results(None))["task_split_overhead"] == "n/a"
