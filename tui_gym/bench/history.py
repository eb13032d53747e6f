"""The run history's cost: recording's share of a `train` run, and the file's size."""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from tui_gym.bench.figures import median

OVERHEAD_TARGET = 0.02  # recording's share of a train run
SIZE_TARGET_BYTES = 1_000_000  # per 1,000 runs
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

    @property
    def overhead(self) -> float:
        return median(self.shares)

    @property
    def ab_ratio(self) -> float:
        """Fastest recorded run ÷ fastest unrecorded run."""
        return min(self.recorded_s) / min(self.unrecorded_s)

    @property
    def bytes_per_1000(self) -> float:
        return self.size_bytes * 1000 / self.runs


def _timed_recording(db: Path, spent: list[float]) -> Any:
    """A `TrainRecording` that adds the time of each of its calls to `spent[0]`."""
    from tui_gym.session.experiments.train_recording import TrainRecording

    class Timed(TrainRecording):
        pass

    for name in ("begin", "on_chunk", "finish", "close"):
        method = getattr(TrainRecording, name)

        def timed(self: Any, *args: Any, _method: Any = method, **kwargs: Any) -> Any:
            started = time.perf_counter()
            try:
                return _method(self, *args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - started

        setattr(Timed, name, timed)
    started = time.perf_counter()
    recording = Timed(str(db))
    spent[0] += time.perf_counter() - started
    return recording


def _train_once(db: Path, record: bool) -> tuple[float, float]:
    """One default train run as `tui-gym train blackjack` runs it (the game's defaults,
    seed 0, then the greedy evaluation): (whole seconds, recording seconds)."""
    from tui_gym.session.experiments.train_recording import TrainRecording
    from tui_gym.session.session import Session

    spent = [0.0]
    started = time.perf_counter()
    recording = _timed_recording(db, spent) if record else TrainRecording(enabled=False)
    with recording:
        session = Session(GAME, seed=0)
        recording.begin(session)
        session.train(on_chunk=recording.on_chunk)
        report = session.evaluate(EVAL_EPISODES, seed=1)
        recording.finish(report)
    return time.perf_counter() - started, spent[0]


def _size(db: Path, template: Path, runs: int) -> int:
    """The size of a fresh history holding `runs` copies of the template's last run."""
    from tui_gym.core.experiments import Curve, RunHistory, RunSpec, RunStatus

    with RunHistory(template) as history:
        record = history.get_run(history.list_runs(limit=1)[0].id)
    spec = RunSpec(
        kind=record.summary.kind, game=record.summary.game, algorithm=record.summary.algorithm,
        game_params=record.game_params, wrappers=record.wrappers,
        hyperparameters=record.hyperparameters, versions=record.versions,
    )
    rng = np.random.default_rng(0)
    with RunHistory(db) as history:
        for seed in range(runs):
            run_id = history.start_run(replace(spec, seeds=(seed,)))
            curves = [
                Curve(c.name, c.episodes, c.values + rng.normal(0.0, 0.01, len(c)))
                for c in record.curves
            ]
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


# --- what the report shows ---------------------------------------------------------
def verdicts(result: HistoryResult | None, missing: str, ok: Any) -> dict[str, str]:
    """The verdicts of the two targets (`ok(value, good)` as the report's)."""
    if result is None:
        return {"history_overhead": missing, "history_bytes_per_1000_runs": missing}
    return {
        "history_overhead": ok(result.overhead, result.overhead <= OVERHEAD_TARGET),
        "history_bytes_per_1000_runs": ok(
            result.bytes_per_1000, result.bytes_per_1000 < SIZE_TARGET_BYTES
        ),
    }


def to_json(result: HistoryResult | None) -> dict[str, Any] | None:
    if result is None:
        return None
    return {
        "game": result.game, "overhead": result.overhead, "overhead_samples": list(result.shares),
        "recorded_run_s": list(result.recorded_s), "unrecorded_run_s": list(result.unrecorded_s),
        "fastest_recorded_over_unrecorded": result.ab_ratio, "runs_written": result.runs,
        "size_bytes": result.size_bytes, "bytes_per_1000_runs": result.bytes_per_1000,
    }


def rows(result: HistoryResult | None) -> list[tuple[str, str, str, str | None]]:
    """(figure, measured, target, verdict key) rows for the bench table."""
    if result is None:
        return []
    return [
        (f"run history: recording's share of a train {result.game} run",
         f"{result.overhead:.2%} (median of {len(result.shares)})",
         f"≤ {OVERHEAD_TARGET:.0%}", "history_overhead"),
        ("  whole run, fastest recorded ÷ fastest --no-record (noisy)",
         f"{result.ab_ratio:.3f} ({min(result.recorded_s):.2f} s / "
         f"{min(result.unrecorded_s):.2f} s)", "", None),
        (f"run history: file size per 1,000 default runs ({result.runs:,} written)",
         f"{result.bytes_per_1000 / 1e6:.3f} MB", f"< {SIZE_TARGET_BYTES / 1e6:g} MB",
         "history_bytes_per_1000_runs"),
    ]
