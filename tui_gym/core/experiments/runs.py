"""What `tui-gym runs` does, as plain functions returning typed results for the CLI to print.

`list_runs` (`runs [--json] [--game G]`), `show_run` (`runs show ID`),
`export_run_csv` (`runs export ID --csv PATH`) and `remove_run` (`runs rm ID`).
Each takes `db`, the `--db` value (None for `TUI_GYM_DB` or the data folder's
file). Reading never creates a file: with no history yet there are no runs.
Every problem raises a `RunHistoryError` whose message is one line to show.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tui_gym.core.experiments.csv_export import curves_csv
from tui_gym.core.experiments.errors import RunHistoryError, UnknownRunError
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.paths import resolve_db_path
from tui_gym.core.experiments.records import RunKind, RunRecord, RunSummary
from tui_gym.core.files import OutputPathError, check_output_path, write_atomically


@dataclass(frozen=True)
class RunListing:
    """The runs of one history file, newest first."""

    db: Path
    runs: tuple[RunSummary, ...]

    def to_json(self) -> dict[str, Any]:
        return {"db": str(self.db), "runs": [run.to_json() for run in self.runs]}


@dataclass(frozen=True)
class CsvExport:
    """A run's curves written to `path`: its columns (episode first) and number of rows."""

    run_id: int
    path: Path
    columns: tuple[str, ...]
    rows: int

    def to_json(self) -> dict[str, Any]:
        return {
            "run": self.run_id,
            "path": str(self.path),
            "columns": list(self.columns),
            "rows": self.rows,
        }


@dataclass(frozen=True)
class RemovedRun:
    """A run that was removed from `db`."""

    db: Path
    run: RunSummary

    def to_json(self) -> dict[str, Any]:
        return {"db": str(self.db), "removed": self.run.to_json()}


def _existing(db: str | None) -> tuple[Path, bool]:
    path = resolve_db_path(db)
    return path, path.exists() and path.stat().st_size > 0


def list_runs(
    db: str | None = None,
    *,
    game: str | None = None,
    kind: RunKind | str | None = None,
    limit: int | None = None,
) -> RunListing:
    """The recorded runs, newest first (only `game`'s and `kind`'s when given)."""
    path, exists = _existing(db)
    if not exists:
        return RunListing(db=path, runs=())
    with RunHistory(path) as history:
        return RunListing(db=path, runs=tuple(history.list_runs(game=game, kind=kind, limit=limit)))


def show_run(run_id: int, db: str | None = None) -> RunRecord:
    """Everything about one run."""
    path, exists = _existing(db)
    if not exists:
        raise UnknownRunError(f"no run {run_id} in {path} (no runs are recorded there yet)")
    with RunHistory(path) as history:
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
        raise RunHistoryError(f"cannot write {target}: {exc.strerror or exc}") from None
    columns = ("episode", *(c.name for c in record.curves))
    return CsvExport(run_id=run_id, path=target, columns=columns, rows=rows)


def remove_run(run_id: int, db: str | None = None) -> RemovedRun:
    """Delete one run (its curves and figures with it)."""
    path, exists = _existing(db)
    if not exists:
        raise UnknownRunError(f"no run {run_id} in {path} (no runs are recorded there yet)")
    with RunHistory(path) as history:
        return RemovedRun(db=path, run=history.remove_run(run_id))
