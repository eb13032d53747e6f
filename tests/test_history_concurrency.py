"""Two processes recording into one run history at once lose nothing."""

from __future__ import annotations

import multiprocessing
from multiprocessing.synchronize import Barrier
from pathlib import Path

import numpy as np

from tui_gym.core.experiments import Curve, Figure, RunHistory, RunKind, RunSpec, RunStatus

RUNS_EACH = 50


def record_runs(path: str, writer: int, start: Barrier) -> None:
    """One process: wait for the other, then open the (new) file and record RUNS_EACH runs."""
    start.wait(timeout=60)
    curve = np.linspace(-1.0, 0.0, 500)
    with RunHistory(path) as history:
        for i in range(RUNS_EACH):
            run_spec = RunSpec(
                kind=RunKind.TRAIN, game="blackjack", algorithm=f"writer{writer}", seeds=(i,)
            )
            run_id = history.start_run(run_spec)
            history.update(
                run_id,
                curves=[Curve.per_episode("return", curve)],
                figures=[Figure("writer", writer)],
                status=RunStatus.FINISHED,
            )


def test_two_processes_recording_at_once(tmp_path: Path) -> None:
    path = tmp_path / "fresh" / "runs.db"  # neither folder nor file exists yet
    ctx = multiprocessing.get_context("spawn")
    start = ctx.Barrier(2)
    workers = [ctx.Process(target=record_runs, args=(str(path), w, start)) for w in (0, 1)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(timeout=120)
    assert [w.exitcode for w in workers] == [0, 0]
    with RunHistory(path) as history:
        runs = history.list_runs()
        assert len(runs) == 2 * RUNS_EACH
        for writer in (0, 1):
            mine = [r for r in runs if r.algorithm == f"writer{writer}"]
            assert sorted(r.seeds[0] for r in mine) == list(range(RUNS_EACH))
            assert all(r.status is RunStatus.FINISHED for r in mine)
            assert all(r.figures == (Figure("writer", writer),) for r in mine)
        record = history.get_run(runs[0].id)
        curve = record.curve("return")
        assert curve is not None and curve.episodes[-1] == 500
