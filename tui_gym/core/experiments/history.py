"""The run history: every run recorded in one SQLite file that any number of processes share
(`RunHistory`), and one run being recorded into it (`RunRecorder`)."""

from __future__ import annotations

import math
import sqlite3
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import astuple, dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, TypeVar

import numpy as np

import tui_gym.core.experiments.rows as rows
from tui_gym.core.experiments.aggregate import CurveAccumulator, bucket_means
from tui_gym.core.experiments.codec import (
    BadTask,
    CurveFormatError,
    decode,
    decode_rows,
    encode,
    encode_curve,
    pack_curves,
    unpack_curves,
)
from tui_gym.core.experiments.connection import (
    MIGRATIONS,
    Migration,
    WriterCheck,
    check_migrations,
    current_writer,
    damaged,
    is_damage,
    open_shared,
    release,
    shown,
)
from tui_gym.core.experiments.errors import DamagedRunError, RunHistoryError, UnknownRunError
from tui_gym.core.experiments.figures import FieldsJson, Figure
from tui_gym.core.experiments.records import (
    Curve,
    RunKind,
    RunRecord,
    RunSpec,
    RunStatus,
    RunSummary,
    TaskRecord,
    Versions,
    to_json_text,
)

# Points kept per stored curve: about a terminal chart's width, and few enough that a
# thousand runs with a few curves each stay within the history's size budget.
STORED_POINTS = 100
MAX_STORED_POINTS = 500
BUSY_TIMEOUT_S = 30.0  # how long a read or a write waits for other processes

T = TypeVar("T")


@dataclass(frozen=True)
class DamagedRun(FieldsJson):
    """A run whose row does not read: its id and why, in a few words."""

    id: int
    reason: str


@dataclass(frozen=True)
class RunRows:
    """The runs a query found that read, and those that do not."""

    runs: tuple[RunSummary, ...]
    damaged: tuple[DamagedRun, ...] = ()


class RunHistory:
    """One run history file, open for reading and recording (thread-safe)."""

    def __init__(
        self, path: str | Path, *, timeout: float = BUSY_TIMEOUT_S,
        migrations: Sequence[Migration] = MIGRATIONS, read_only: bool = False,
    ) -> None:
        self.path = Path(path)
        self.timeout = timeout
        self.schema_version = check_migrations(migrations)
        self._shared = open_shared(self.path, migrations, timeout, read_only=read_only)
        self._conn = self._shared.conn
        self._closed = False

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            release(self._shared)

    def __enter__(self) -> RunHistory:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @contextmanager
    def _errors(self) -> Iterator[None]:
        """SQLite's errors as one line naming the file."""
        try:
            yield
        except sqlite3.DatabaseError as exc:
            if is_damage(exc):
                raise damaged(self.path, exc) from None
            raise RunHistoryError(f"{shown(self.path)}: {exc}") from None
        except CurveFormatError as exc:
            raise damaged(self.path, f"a stored curve: {exc}") from None

    def _write(self, write: Callable[[sqlite3.Connection], T]) -> T:
        """`write(conn)` in one write transaction, taken as soon as no one else holds it."""
        return self._attempt(write, "BEGIN IMMEDIATE")

    def _read(self, read: Callable[[sqlite3.Connection], T]) -> T:
        """`read(conn)` in one read transaction (one state of the file)."""
        return self._attempt(read, "BEGIN")

    def _attempt(self, action: Callable[[sqlite3.Connection], T], begin: str | None) -> T:
        if self._closed:
            raise RunHistoryError(f"{shown(self.path)}: this history was closed")
        with self._errors():
            return self._shared.attempt(action, self.timeout, self.path, begin=begin)

    def _require_run(self, conn: sqlite3.Connection, run_id: int, columns: str = "1",
                     source: str = "FROM runs WHERE id = ?") -> Any:
        """The run's `columns`; UnknownRunError if there is no such run."""
        row = conn.execute(f"SELECT {columns} {source}", (run_id,)).fetchone()
        if row is None:
            raise UnknownRunError(f"no run {run_id} in {shown(self.path)}")
        return row

    def _stored_curves(self, run_id: int, blob: object) -> dict[str, bytes]:
        """A run's stored curves by name, to add to; DamagedRunError if they do not read."""
        try:
            if not isinstance(blob, bytes):
                raise CurveFormatError("not a blob")
            return unpack_curves(blob)
        except CurveFormatError as exc:
            raise self._damaged_run(run_id, f"its curves do not decode ({exc})") from None

    def _damaged_run(self, run_id: int, reason: str) -> DamagedRunError:
        return DamagedRunError(
            run_id,
            f"run {run_id} in {shown(self.path)} cannot be read: {reason} "
            f"(`tui-gym runs rm {run_id}` removes it)",
        )

    def start_run(self, spec: RunSpec, started_at: float | None = None) -> int:
        """Record a new run (status running); its id."""
        started = time.time() if started_at is None else started_at
        settings = _settings(spec)
        platform = astuple(spec.versions or Versions.current())
        seeds = to_json_text(list(spec.seeds), "the seeds")
        row = dict(kind=str(spec.kind), seeds=seeds, status=str(RunStatus.RUNNING),
                   started_at=started, group_id=spec.group, writer=current_writer())
        return self._write(lambda conn: _insert_run(conn, settings, platform, **row))

    def update(
        self, run_id: int, *, curves: Iterable[Curve] = (), figures: Iterable[Figure] = (),
        agent_path: str | Path | None = None, status: RunStatus | None = None,
        ended_at: float | None = None, max_points: int = STORED_POINTS, spec: RunSpec | None = None,
    ) -> None:
        """Add or replace curves (each bounded to `max_points`) and figures by name, and set
        what is given of the saved agent's path, the settings of `spec`, a final status."""
        if not 2 <= max_points <= MAX_STORED_POINTS:
            raise ValueError(f"max_points must be in 2..{MAX_STORED_POINTS}, got {max_points}")
        blobs = _encoded(curves, max_points)
        figure_rows = list(figures)
        settings = None if spec is None else _settings(spec)
        final = None if status is None else RunStatus(status)
        if final is RunStatus.RUNNING:
            raise ValueError("a run can only be set to a final status")
        ended = None if final is None else (time.time() if ended_at is None else ended_at)

        def write(conn: sqlite3.Connection) -> None:
            figures_text, old_id = self._require_run(conn, run_id, "figures, settings_id")
            if blobs:
                row = conn.execute("SELECT data FROM curves WHERE run_id = ?", (run_id,)).fetchone()
                stored = {} if row is None else self._stored_curves(run_id, row[0])
                stored.update(blobs)
                conn.execute(
                    "INSERT OR REPLACE INTO curves (run_id, data) VALUES (?, ?)",
                    (run_id, pack_curves(dict(sorted(stored.items())))),
                )
            sets: dict[str, Any] = {}
            if figure_rows:
                try:
                    merged = {f.name: f for f in rows.figures(figures_text)}
                except rows.BadRow as exc:
                    raise self._damaged_run(run_id, str(exc)) from None
                merged.update((f.name, f) for f in figure_rows)  # a known name keeps its place
                sets["figures"] = _figures_to_json(merged.values())
            if settings is not None:
                sets["settings_id"] = _row_id(conn, "settings", settings)
            if agent_path is not None:
                sets["agent_path"] = str(agent_path)
            if final is not None:
                sets.update(status=str(final), ended_at=ended)
            if sets:
                assignments = ", ".join(f"{name} = ?" for name in sets)
                conn.execute(f"UPDATE runs SET {assignments} WHERE id = ?",
                             (*sets.values(), run_id))
            if settings is not None:
                _drop_unused(conn, "settings", "settings_id", old_id)

        self._write(write)

    def put_task(self, run_id: int, task: TaskRecord) -> bool:
        """Keep a finished task in a transaction of its own; False (nothing written) when the run
        already holds one of its seeds: a task that lands twice is kept once."""
        first, inputs, returns, exact = encode(task)
        when = time.time()

        def write(conn: sqlite3.Connection) -> bool:
            self._require_run(conn, run_id)
            held: set[int] = set()
            for (text,) in conn.execute("SELECT inputs FROM tasks WHERE run_id = ?", (run_id,)):
                try:
                    held.update(decode_rows(text))
                except BadTask as exc:
                    raise self._damaged_run(run_id, f"a task: {exc}") from None
            if held.intersection(task.rows):
                return False
            conn.execute(
                "INSERT INTO tasks (run_id, first_row, inputs, returns, exact, finished_at)"
                " VALUES (?, ?, ?, ?, ?, ?)", (run_id, first, inputs, returns, exact, when))
            return True

        return bool(self._write(write))

    def read_tasks(self, run_id: int) -> list[TaskRecord]:
        """A run's finished tasks, by their first row; DamagedRunError if one does not read."""
        found = self._read(lambda conn: conn.execute(
            "SELECT inputs, returns, exact FROM tasks WHERE run_id = ? ORDER BY first_row",
            (run_id,)).fetchall())
        try:
            return [decode(*row) for row in found]
        except BadTask as exc:
            raise self._damaged_run(run_id, f"a task: {exc}") from None

    def prune_tasks(self) -> tuple[int, int]:
        """Delete the finished runs' stored tasks (only an unfinished run needs them, to
        resume) and give the space back; (runs, tasks) pruned."""
        finished = (str(RunStatus.FINISHED),)
        where = "WHERE run_id IN (SELECT id FROM runs WHERE status = ?)"

        def write(conn: sqlite3.Connection) -> tuple[int, int]:
            runs, tasks = conn.execute(
                f"SELECT COUNT(DISTINCT run_id), COUNT(*) FROM tasks {where}", finished).fetchone()
            conn.execute(f"DELETE FROM tasks {where}", finished)
            return int(runs), int(tasks)

        pruned = self._write(write)
        if pruned[1]:
            self._attempt(lambda conn: conn.execute("VACUUM"), begin=None)
        return pruned

    def group_ids(self, run_id: int) -> list[int]:
        """Run `run_id` and the runs of its group, by id; UnknownRunError if there is none."""

        def read(conn: sqlite3.Connection) -> list[int]:
            self._require_run(conn, run_id)
            return [int(r[0]) for r in conn.execute(
                "SELECT id FROM runs WHERE id = ? OR group_id = ? ORDER BY id", (run_id, run_id))]

        return self._read(read)

    def reopen_run(self, run_id: int) -> None:
        """Mark a run running again, by this process (it resumes)."""
        writer = current_writer()

        def write(conn: sqlite3.Connection) -> None:
            self._require_run(conn, run_id)
            conn.execute("UPDATE runs SET status = ?, ended_at = NULL, writer = ? WHERE id = ?",
                         (str(RunStatus.RUNNING), writer, run_id))

        self._write(write)

    def restore_run(self, record: RunRecord, writer: str | None = None) -> None:
        """Write a run read elsewhere under its own id (`recover`): its settings, times,
        status, figures, curves and saved agent's path, and the mark of its writer."""
        run = record.summary
        settings = _settings(RunSpec(
            kind=run.kind, game=run.game, algorithm=run.algorithm,
            game_params=record.game_params, wrappers=record.wrappers,
            hyperparameters=record.hyperparameters,
        ))
        platform = astuple(record.versions)
        blob = pack_curves(_encoded(record.curves, MAX_STORED_POINTS))

        def write(conn: sqlite3.Connection) -> None:
            _insert_run(conn, settings, platform, id=run.id, kind=str(run.kind),
                        seeds=to_json_text(list(run.seeds), "the seeds"), status=str(run.status),
                        started_at=run.started_at, ended_at=run.ended_at,
                        agent_path=record.agent_path, group_id=run.group,
                        figures=_figures_to_json(run.figures), writer=writer)
            if record.curves:
                conn.execute("INSERT INTO curves (run_id, data) VALUES (?, ?)", (run.id, blob))

        self._write(write)

    def read_runs(
        self, *, game: str | None = None, kind: RunKind | str | None = None,
        limit: int | None = None,
    ) -> RunRows:
        """The runs, newest first (at most `limit`; only those of `game` and `kind` when
        given), each checked as it is read: those that do not read come apart, by id."""
        where, args = _where(game, kind)
        sql = f"SELECT {rows.SUMMARY_COLUMNS} {rows.SUMMARY_FROM}{where}" \
              " ORDER BY r.started_at DESC, r.id DESC"
        if limit is not None:
            sql += " LIMIT ?"
            args.append(int(limit))
        found = self._read(lambda conn: conn.execute(sql, args).fetchall())
        writers = WriterCheck()
        runs: list[RunSummary] = []
        bad: list[DamagedRun] = []
        for row in found:
            try:
                runs.append(rows.summary(row, writers))
            except rows.BadRow as exc:
                bad.append(DamagedRun(int(row[0]), str(exc)))
        return RunRows(tuple(runs), tuple(bad))

    def list_runs(
        self, *, game: str | None = None, kind: RunKind | str | None = None,
        limit: int | None = None,
    ) -> list[RunSummary]:
        """The runs that read, newest first (see `read_runs`, which also names the others)."""
        return list(self.read_runs(game=game, kind=kind, limit=limit).runs)

    def count_runs(self, *, game: str | None = None, kind: RunKind | str | None = None) -> int:
        """How many runs there are (of `game` and `kind` when given)."""
        where, args = _where(game, kind)
        sql = f"SELECT COUNT(*) {rows.SUMMARY_FROM}{where}"
        return int(self._read(lambda conn: conn.execute(sql, args).fetchone()[0]))

    def get_run(self, run_id: int) -> RunRecord:
        """Everything about one run; UnknownRunError if there is none with that id,
        DamagedRunError (one line naming it) if its row does not read."""

        def read(conn: sqlite3.Connection) -> tuple[Any, Any]:
            row = self._require_run(conn, run_id, rows.RECORD_COLUMNS,
                                    f"{rows.RECORD_FROM} WHERE r.id = ?")
            blob = conn.execute(
                f"SELECT {rows.CURVES_COLUMNS} FROM curves WHERE run_id = ?", (run_id,)
            ).fetchone()
            return row, blob

        row, blob = self._read(read)
        try:
            curves = () if blob is None else rows.curves(*blob)
            return rows.record(row, curves, WriterCheck())
        except rows.BadRow as exc:
            raise self._damaged_run(run_id, str(exc)) from None

    def remove_run(self, run_id: int) -> RunSummary | DamagedRun:
        """Delete a run with its curves and figures; what it was (a `DamagedRun` for a run
        whose row did not read: removing it is how it goes)."""

        def write(conn: sqlite3.Connection) -> RunSummary | DamagedRun:
            row = self._require_run(conn, run_id,
                                    f"{rows.SUMMARY_COLUMNS}, r.settings_id, r.platform_id",
                                    f"{rows.SUMMARY_FROM} WHERE r.id = ?")
            was: RunSummary | DamagedRun
            try:
                was = rows.summary(row, WriterCheck())
            except rows.BadRow as exc:
                was = DamagedRun(run_id, str(exc))
            settings_id, platform_id = row[-2:]
            conn.execute("DELETE FROM curves WHERE run_id = ?", (run_id,))
            conn.execute("DELETE FROM tasks WHERE run_id = ?", (run_id,))
            conn.execute("DELETE FROM runs WHERE id = ?", (run_id,))
            _drop_unused(conn, "settings", "settings_id", settings_id)
            _drop_unused(conn, "platforms", "platform_id", platform_id)
            return was

        return self._write(write)


class BestEffortHistory(RunHistory):
    """A run history whose writes never raise: once one fails, it and every later write are
    skipped (a run it could not start has the id None), and `failure` says why."""

    failure: str | None = None

    def _write(self, write: Callable[[sqlite3.Connection], T]) -> T:
        if self.failure is None:
            try:
                return super()._write(write)
            except RunHistoryError as exc:
                self.failure = str(exc)
        return None  # type: ignore[return-value]


def _encoded(curves: Iterable[Curve], max_points: int) -> dict[str, bytes]:
    """Each curve's bytes by name, bounded to `max_points` bucket means."""
    return {c.name: encode_curve(*bucket_means(c.episodes, c.values, max_points)) for c in curves}


def _insert_run(conn: sqlite3.Connection, settings: tuple[str, ...], platform: tuple[str, ...],
                **row: Any) -> int:
    """Insert a run of those settings and platform whose other fields are `row`; its id."""
    row.update(settings_id=_row_id(conn, "settings", settings),
               platform_id=_row_id(conn, "platforms", platform))
    names, marks = ", ".join(row), ", ".join("?" * len(row))
    cursor = conn.execute(f"INSERT INTO runs ({names}) VALUES ({marks})", tuple(row.values()))
    assert cursor.lastrowid is not None
    return cursor.lastrowid


def _where(game: str | None, kind: RunKind | str | None) -> tuple[str, list[Any]]:
    clauses, args = [], []
    if game is not None:
        clauses.append("s.game = ? COLLATE NOCASE")
        args.append(game)
    if kind is not None:
        clauses.append("r.kind = ?")
        args.append(str(RunKind(kind)))
    return ("" if not clauses else " WHERE " + " AND ".join(clauses)), args


_COLUMNS = {  # of the rows runs share
    "settings": ("game", "game_params", "wrappers", "algorithm", "hyperparameters"),
    "platforms": ("tui_gym", "gymnasium", "numpy", "python"),
}


def _settings(spec: RunSpec) -> tuple[str, ...]:
    return (
        spec.game, to_json_text(dict(spec.game_params), "the game's parameters"),
        to_json_text([w.to_json() for w in spec.wrappers], "the wrappers"), spec.algorithm,
        to_json_text(dict(spec.hyperparameters), "the hyperparameters"),
    )


def _row_id(conn: sqlite3.Connection, table: str, values: tuple[str, ...]) -> int:
    """The id of the row of `table` holding exactly `values`, inserted if there is none."""
    columns = _COLUMNS[table]
    names = ", ".join(columns)
    marks = ", ".join("?" * len(columns))
    conn.execute(f"INSERT OR IGNORE INTO {table} ({names}) VALUES ({marks})", values)
    where = " AND ".join(f"{c} = ?" for c in columns)
    row = conn.execute(f"SELECT id FROM {table} WHERE {where}", values).fetchone()
    return int(row[0])


def _drop_unused(conn: sqlite3.Connection, table: str, column: str, row_id: object) -> None:
    """Settings and platforms no run uses any more go."""
    conn.execute(
        f"DELETE FROM {table} WHERE id = ? AND NOT EXISTS (SELECT 1 FROM runs WHERE {column} = ?)",
        (row_id, row_id),
    )


def _figures_to_json(figures: Iterable[Figure]) -> str:
    # SQLite and JSON have no NaN: a figure without a value is stored as null.
    return to_json_text(
        [[f.name, f.value if math.isfinite(f.value) else None, f.unit, f.ci95] for f in figures],
        "the figures",
    )


class RunRecorder:
    """Records one run into a `RunHistory`; `run_id` is its id there."""

    def __init__(self, history: RunHistory, spec: RunSpec) -> None:
        self.history = history
        self.run_id = history.start_run(spec)
        self.status = RunStatus.RUNNING
        self._accumulators: dict[str, CurveAccumulator] = {}
        self._curves: dict[str, Curve] = {}
        self._figures: dict[str, Figure] = {}

    def extend(self, name: str, values: np.ndarray | Iterable[float]) -> None:
        """Append the values of the next episodes to the per-episode curve `name`."""
        values = values if isinstance(values, np.ndarray) else list(values)
        # Twice the stored points, so the stored curve is re-bucketed from finer buckets.
        self._accumulators.setdefault(name, CurveAccumulator(2 * STORED_POINTS)).extend(
            np.asarray(values))

    def put_curve(self, curve: Curve) -> None:
        """A whole curve (say, values at checkpoints), replacing any of the same name."""
        self._curves[curve.name] = curve

    def add_figures(self, *figures: Figure) -> None:
        """Final figures, replacing any of the same name."""
        for figure in figures:
            self._figures[figure.name] = figure

    def flush(self, status: RunStatus | None = None) -> None:
        """Write what the run has so far (and `status`, if given) in one transaction."""
        curves = {**self._curves, **{name: Curve(name, *a.curve(STORED_POINTS))
                                     for name, a in self._accumulators.items() if a.count}}
        self.history.update(self.run_id, curves=curves.values(), status=status,
                            figures=self._figures.values())

    def finish(self, status: RunStatus = RunStatus.FINISHED) -> None:
        """Write everything with the run's final status."""
        self.flush(status)
        self.status = RunStatus(status)

    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self.status is RunStatus.RUNNING:
            self.finish(RunStatus.ending(exc_type))
