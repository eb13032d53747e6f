"""The run history's cost: recording's share of a `train` run, and the file's size."""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from tui_gym.bench.live import after_each

GAME = "blackjack"
EVAL_EPISODES = 10_000  # as `train`'s --eval-episodes by default


@dataclass(frozen=True)
class HistoryResult:
    """Recording's share of each train run, the A/B times, and the file size."""

    game: str
    shares: tuple[float, ...]  # recording time / run time, per recorded run
    recorded_s: tuple[float, ...]  # whole runs, recorded
    unrecorded_s: tuple[float, ...]  # whole runs, --no-record
    runs: int  # written for the size figure
    size_bytes: int


def _train_once(db: Path, record: bool) -> tuple[float, float]:
    """One default train run as `tui-gym train blackjack` runs it (the game's defaults,
    seed 0, then the greedy evaluation): (whole seconds, recording seconds)."""
    from tui_gym.session.experiments.train_recording import TrainRecording
    from tui_gym.session.session import Session

    started = time.perf_counter()
    recording = TrainRecording(str(db), enabled=record)
    spent = [time.perf_counter() - started] if record else [0.0]  # its opening, then its calls
    for name in ("begin", "on_chunk", "finish", "close") if record else ():
        after_each(recording, name, lambda began, *_: spent.append(time.perf_counter() - began))
    with recording:
        session = Session(GAME, seed=0)
        recording.begin(session)
        session.train(on_chunk=recording.on_chunk)
        report = session.evaluate(EVAL_EPISODES, seed=1)
        recording.finish(report)
    return time.perf_counter() - started, sum(spent)


def _size(db: Path, template: Path, runs: int) -> int:
    """The size of a fresh history holding `runs` copies of the template's last run."""
    from tui_gym.core.experiments import Curve, RunHistory, RunSpec, RunStatus

    with RunHistory(template) as history:
        record = history.get_run(history.list_runs(limit=1)[0].id)
    run = record.summary
    spec = RunSpec(run.kind, run.game, run.algorithm, record.game_params, record.wrappers,
                   record.hyperparameters, versions=record.versions)
    rng = np.random.default_rng(0)
    with RunHistory(db) as history:
        for seed in range(runs):
            run_id = history.start_run(replace(spec, seeds=(seed,)))
            curves = [Curve(c.name, c.episodes, c.values + rng.normal(0.0, 0.01, len(c)))
                      for c in record.curves]
            history.update(run_id, curves=curves, figures=record.summary.figures,
                           status=RunStatus.FINISHED)
    return db.stat().st_size


def measure(repeats: int, runs: int = 1000) -> HistoryResult:
    """Recording's share of `repeats` default train runs, and the size of `runs` runs."""
    with tempfile.TemporaryDirectory(prefix="tui-gym-bench-") as tmp:
        folder = Path(tmp)
        db = folder / "runs.db"
        _train_once(db, record=True)  # warm-up: imports, the file's creation
        shares, recorded, unrecorded = [], [], []
        for _ in range(repeats):
            seconds, spent = _train_once(db, record=True)
            shares.append(spent / seconds)
            recorded.append(seconds)
            unrecorded.append(_train_once(db, record=False)[0])
        size = _size(folder / "size.db", db, runs)
    return HistoryResult(GAME, tuple(shares), tuple(recorded), tuple(unrecorded), runs, size)
