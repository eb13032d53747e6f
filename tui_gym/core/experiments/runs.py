"""What `tui-gym runs` does, as plain functions returning typed results for the CLI to print."""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tui_gym.core.experiments.connection import examine, shown
from tui_gym.core.experiments.errors import RunHistoryError, UnknownRunError
from tui_gym.core.experiments.figures import FieldsJson
from tui_gym.core.experiments.history import DamagedRun, RunHistory
from tui_gym.core.experiments.paths import resolve_db_path
from tui_gym.core.experiments.records import Curve, RunKind, RunRecord, RunSummary
from tui_gym.core.files import OutputPathError, check_output_path, write_atomically


@dataclass(frozen=True)
class RunListing(FieldsJson):
    """The runs of one history file, newest first: those that read, those that do not,
    and how many there are in all (`total`; more than listed past a limit)."""

    db: Path
    runs: tuple[RunSummary, ...]
    damaged: tuple[DamagedRun, ...] = ()
    total: int = 0


@dataclass(frozen=True)
class CsvExport(FieldsJson):
    """Run `run`'s curves written to `path`: its columns (episode first) and number of rows."""

    run: int
    path: Path
    columns: tuple[str, ...]
    rows: int


@dataclass(frozen=True)
class RemovedRun:
    """A run that was removed from `db` (a `DamagedRun` when its row did not read)."""

    db: Path
    run: RunSummary | DamagedRun

    def to_json(self) -> dict[str, Any]:
        return {"db": str(self.db), "removed": self.run.to_json()}


def _existing(db: str | None) -> tuple[Path, bool]:
    path = resolve_db_path(db)
    status = examine(path)
    return path, status is not None and status.st_size > 0


def _holding(run_id: int, db: str | None) -> Path:
    """The history's file; UnknownRunError when no run is recorded there yet."""
    path, exists = _existing(db)
    if not exists:
        raise UnknownRunError(f"no run {run_id} in {shown(path)} (no runs are recorded there yet)")
    return path


def list_runs(
    db: str | None = None, *, game: str | None = None, kind: RunKind | str | None = None,
    limit: int | None = None,
) -> RunListing:
    """The recorded runs, newest first (at most `limit`, of `game` and `kind` when given)."""
    path, exists = _existing(db)
    if not exists:
        return RunListing(db=path, runs=())
    with RunHistory(path, read_only=True) as history:
        found = history.read_runs(game=game, kind=kind, limit=limit)
        total = history.count_runs(game=game, kind=kind)
    return RunListing(db=path, runs=found.runs, damaged=found.damaged, total=total)


def show_run(run_id: int, db: str | None = None) -> RunRecord:
    """Everything about one run."""
    with RunHistory(_holding(run_id, db), read_only=True) as history:
        return history.get_run(run_id)


def export_run_csv(run_id: int, csv_path: str | Path, db: str | None = None) -> CsvExport:
    """Write a run's curves to `csv_path` (atomically), one row per episode."""
    try:
        target = check_output_path(csv_path)
    except OutputPathError as error:
        raise RunHistoryError(str(error)) from None
    record = show_run(run_id, db)
    text, rows = curves_csv(record.curves)
    try:
        write_atomically(target, text)
    except OutputPathError as error:
        raise RunHistoryError(str(error)) from None
    except OSError as exc:
        raise RunHistoryError(f"cannot write {shown(target)}: {exc.strerror or exc}") from None
    columns = ("episode", *(c.name for c in record.curves))
    return CsvExport(run=run_id, path=target, columns=columns, rows=rows)


def remove_run(run_id: int, db: str | None = None) -> RemovedRun:
    """Delete one run (its curves and figures with it), whether or not it reads."""
    path = _holding(run_id, db)
    with RunHistory(path) as history:
        return RemovedRun(db=path, run=history.remove_run(run_id))


@dataclass(frozen=True)
class PrunedTasks(FieldsJson):
    """The stored tasks `prune_tasks` removed from `db`: `tasks` of `runs` finished runs."""

    db: Path
    runs: int
    tasks: int


def prune_tasks(db: str | None = None) -> PrunedTasks:
    """Remove the stored tasks of the finished runs (see `RunHistory.prune_tasks`)."""
    path, exists = _existing(db)
    if not exists:
        return PrunedTasks(path, 0, 0)
    with RunHistory(path) as history:
        return PrunedTasks(path, *history.prune_tasks())


def curves_csv(curves: Sequence[Curve]) -> tuple[str, int]:
    """The CSV text of `curves` and its number of rows: one an episode, one column a curve,
    floats in full (`repr`), an empty cell where a curve has no value."""
    none: np.ndarray = np.empty(0, dtype=np.int64)
    episodes = np.unique(np.concatenate([c.episodes for c in curves])) if curves else none
    columns: list[list[str]] = []
    for curve in curves:
        cells = [""] * len(episodes)
        at = np.searchsorted(episodes, curve.episodes)
        for i, value in zip(at.tolist(), curve.values.tolist(), strict=True):
            cells[i] = "" if value != value else repr(value)  # NaN: no value here
        columns.append(cells)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["episode", *(c.name for c in curves)])
    for row, episode in enumerate(episodes.tolist()):
        writer.writerow([episode, *(cells[row] for cells in columns)])
    return out.getvalue(), len(episodes)
