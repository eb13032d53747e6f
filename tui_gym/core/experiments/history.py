"""The run history: every run recorded in one SQLite file that any number of processes share.

`RunHistory(path)` opens the file, creating it (and its folder) when missing,
and brings an older schema up to date. Before writing anything it checks that
the file is a tui-gym run history: a file that is not SQLite, a damaged one,
another program's database, or one made by a newer tui-gym raises a
`RunHistoryError` naming the file, and the file is left as it was.

The file is in WAL mode, so readers never wait; writers take the write lock
up front (`BEGIN IMMEDIATE`) and wait their turn, retrying past the busy
timeout, so two processes recording at once both get every run in. A run is
written when it starts (status running) and updated as it goes: curves (kept
to at most `STORED_POINTS` bucket means each, see `curve_codec` for the bytes),
figures, the saved agent's path, and finally its status and end time.
"""

from __future__ import annotations

import json
import math
import sqlite3
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

from tui_gym.core.experiments.curve_codec import (
    CurveFormatError,
    decode_curve,
    encode_curve,
    pack_curves,
    unpack_curves,
)
from tui_gym.core.experiments.downsample import bucket_means
from tui_gym.core.experiments.errors import (
    NewerRunHistoryError,
    NotARunHistoryError,
    RunHistoryBusyError,
    RunHistoryError,
    UnknownRunError,
)
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.records import (
    Curve,
    RunKind,
    RunRecord,
    RunSpec,
    RunStatus,
    RunSummary,
    Versions,
    WrapperSetting,
    to_json_text,
)
from tui_gym.core.experiments.schema import (
    APPLICATION_ID,
    MIGRATIONS,
    Migration,
    check_migrations,
    migrate,
)

# Points kept per stored curve: about a terminal chart's width, and few enough that a
# thousand runs with a few curves each stay within the history's size budget.
STORED_POINTS = 100
MAX_STORED_POINTS = 500
BUSY_TIMEOUT_S = 10.0  # how long one attempt waits for another writer
WRITE_ATTEMPTS = 4
SQLITE_MAGIC = b"SQLite format 3\x00"

T = TypeVar("T")


def _is_busy(exc: sqlite3.OperationalError) -> bool:
    text = str(exc).lower()
    return "locked" in text or "busy" in text


def _inspect(conn: sqlite3.Connection) -> tuple[int, int, list[str]]:
    # One read transaction, so that the three answers describe the same state of the file:
    # another process may be creating it (tables first, then the id) at this very moment.
    own = not conn.in_transaction
    if own:
        conn.execute("BEGIN")
    try:
        app_id = conn.execute("PRAGMA application_id").fetchone()[0]
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = [
            row[0]
            for row in conn.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
            )
        ]
    finally:
        if own and conn.in_transaction:
            conn.execute("COMMIT")
    return app_id, version, tables


class RunHistory:
    """One run history file, open for reading and recording (thread-safe)."""

    def __init__(
        self,
        path: str | Path,
        *,
        timeout: float = BUSY_TIMEOUT_S,
        migrations: Sequence[Migration] = MIGRATIONS,
    ) -> None:
        self.path = Path(path)
        self.timeout = timeout
        self.schema_version = check_migrations(migrations)
        self._lock = threading.Lock()
        self._conn = self._open(migrations)

    # -- opening -------------------------------------------------------------

    def _untouched(self, what: str) -> NotARunHistoryError:
        return NotARunHistoryError(
            f"{self.path} is not a tui-gym run history ({what}); it was left untouched"
        )

    def _check_identity(self, app_id: int, version: int, tables: list[str]) -> int:
        """The file's schema version, 0 for an empty file; raises for anything not ours."""
        if app_id == APPLICATION_ID:
            if version > self.schema_version:
                raise NewerRunHistoryError(
                    f"{self.path} was made by a newer tui-gym (run history version {version}; "
                    f"this tui-gym reads up to {self.schema_version}): upgrade tui-gym, "
                    "or record elsewhere with --db PATH"
                )
            return version
        if app_id == 0 and version == 0 and not tables:
            return 0
        if tables:
            shown = ", ".join(tables[:3]) + (", ..." if len(tables) > 3 else "")
            raise self._untouched(f"an SQLite database of another program, with tables {shown}")
        raise self._untouched(f"an SQLite database of another program (application id {app_id})")

    def _check_existing(self) -> None:
        """Checks a non-empty file without writing to it: the header, then a read-only look."""
        try:
            with self.path.open("rb") as fh:
                header = fh.read(len(SQLITE_MAGIC))
        except OSError as exc:
            raise RunHistoryError(f"{self.path}: cannot read it ({exc.strerror})") from None
        if header != SQLITE_MAGIC:
            raise self._untouched("not an SQLite database")
        uri = self.path.resolve().as_uri() + "?mode=ro"
        try:
            conn = sqlite3.connect(uri, uri=True, timeout=self.timeout)
            try:
                identity = _inspect(conn)
            finally:
                conn.close()
        except sqlite3.OperationalError as exc:
            if _is_busy(exc):
                raise self._busy() from None
            raise RunHistoryError(f"{self.path}: cannot read it ({exc})") from None
        except sqlite3.DatabaseError as exc:  # "file is not a database" and the like
            raise self._untouched(str(exc)) from None
        self._check_identity(*identity)

    def _open(self, migrations: Sequence[Migration]) -> sqlite3.Connection:
        if self.path.is_dir():
            raise NotARunHistoryError(f"{self.path} is a folder, not a run history file")
        if self.path.exists() and self.path.stat().st_size > 0:
            self._check_existing()
        else:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise RunHistoryError(
                    f"{self.path}: cannot create its folder ({exc.strerror})"
                ) from None
        try:
            conn = sqlite3.connect(
                self.path, timeout=self.timeout, isolation_level=None, check_same_thread=False
            )
        except sqlite3.Error as exc:
            raise RunHistoryError(f"{self.path}: cannot open it ({exc})") from None
        try:
            with self._errors():
                self._retry(lambda: conn.execute("PRAGMA journal_mode = WAL").fetchone())
                conn.execute("PRAGMA synchronous = NORMAL")  # WAL stays consistent on a crash
                conn.execute("PRAGMA foreign_keys = ON")
                if self._check_identity(*_inspect(conn)) < self.schema_version:

                    def upgrade(c: sqlite3.Connection) -> None:
                        # Another process may have got there first: look again under the lock.
                        migrate(c, self._check_identity(*_inspect(c)), migrations)

                    self._transaction(conn, upgrade)
        except BaseException:
            conn.close()
            raise
        return conn

    def close(self) -> None:
        with self._lock:
            self._conn.close()

    def __enter__(self) -> RunHistory:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- plumbing ------------------------------------------------------------

    def _busy(self) -> RunHistoryBusyError:
        return RunHistoryBusyError(
            f"{self.path} is busy: another process kept it locked for over "
            f"{self.timeout * WRITE_ATTEMPTS:.0f} s"
        )

    @contextmanager
    def _errors(self) -> Iterator[None]:
        """SQLite's errors as one line naming the file."""
        try:
            yield
        except sqlite3.OperationalError as exc:
            if _is_busy(exc):
                raise self._busy() from None
            raise RunHistoryError(f"{self.path}: {exc}") from None
        except sqlite3.DatabaseError as exc:
            raise RunHistoryError(f"{self.path} is damaged ({exc})") from None
        except CurveFormatError as exc:
            raise RunHistoryError(f"{self.path} is damaged (a stored curve: {exc})") from None

    @contextmanager
    def _damaged_rows(self) -> Iterator[None]:
        """Rows that do not read as what this version wrote, as one line naming the file."""
        try:
            yield
        except (ValueError, KeyError, TypeError) as exc:
            raise RunHistoryError(f"{self.path} is damaged (a run reads as {exc!r})") from None

    def _retry(self, action: Callable[[], T]) -> T:
        for attempt in range(WRITE_ATTEMPTS):
            try:
                return action()
            except sqlite3.OperationalError as exc:
                if not _is_busy(exc) or attempt + 1 == WRITE_ATTEMPTS:
                    raise
                time.sleep(0.01 * 2**attempt)  # the busy timeout already waited; back off a little
        raise AssertionError("unreachable")

    def _transaction(self, conn: sqlite3.Connection, write: Callable[[sqlite3.Connection], T]) -> T:
        """`write(conn)` inside one write transaction, taken as soon as no one else holds it."""
        self._retry(lambda: conn.execute("BEGIN IMMEDIATE"))
        try:
            result = write(conn)
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise
        return result

    def _write(self, write: Callable[[sqlite3.Connection], T]) -> T:
        with self._lock, self._errors():
            return self._transaction(self._conn, write)

    @contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        with self._lock, self._errors():
            yield self._conn

    def _require_run(self, conn: sqlite3.Connection, run_id: int) -> None:
        if conn.execute("SELECT 1 FROM runs WHERE id = ?", (run_id,)).fetchone() is None:
            raise UnknownRunError(f"no run {run_id} in {self.path}")

    # -- recording -----------------------------------------------------------

    def start_run(self, spec: RunSpec, started_at: float | None = None) -> int:
        """Record a new run (status running); its id."""
        versions = spec.versions or Versions.current()
        settings = (
            spec.game,
            to_json_text(dict(spec.game_params), "the game's parameters"),
            to_json_text([w.to_json() for w in spec.wrappers], "the wrappers"),
            spec.algorithm,
            to_json_text(dict(spec.hyperparameters), "the hyperparameters"),
        )
        seeds = to_json_text(list(spec.seeds), "the seeds")
        started = time.time() if started_at is None else started_at

        def write(conn: sqlite3.Connection) -> int:
            platform_id = _row_id(
                conn,
                "platforms",
                ("tui_gym", "gymnasium", "numpy", "python"),
                (versions.tui_gym, versions.gymnasium, versions.numpy, versions.python),
            )
            settings_id = _row_id(
                conn,
                "settings",
                ("game", "game_params", "wrappers", "algorithm", "hyperparameters"),
                settings,
            )
            cursor = conn.execute(
                "INSERT INTO runs (kind, settings_id, platform_id, seeds, status, started_at,"
                " group_id) VALUES (?, ?, ?, ?, ?, ?, ?)",
                (
                    str(spec.kind),
                    settings_id,
                    platform_id,
                    seeds,
                    str(RunStatus.RUNNING),
                    started,
                    spec.group,
                ),
            )
            assert cursor.lastrowid is not None
            return cursor.lastrowid

        return self._write(write)

    def update(
        self,
        run_id: int,
        *,
        curves: Iterable[Curve] = (),
        figures: Iterable[Figure] = (),
        agent_path: str | Path | None = None,
        status: RunStatus | None = None,
        ended_at: float | None = None,
        max_points: int = STORED_POINTS,
    ) -> None:
        """Add or replace curves (each bounded to `max_points`) and figures (by name), set the
        saved agent's path (None: leave it), and set a final status with the end time, at once."""
        if not 2 <= max_points <= MAX_STORED_POINTS:
            raise ValueError(f"max_points must be in 2..{MAX_STORED_POINTS}, got {max_points}")
        blobs = [
            (c.name, encode_curve(*bucket_means(c.episodes, c.values, max_points))) for c in curves
        ]
        figure_rows = list(figures)
        final = None if status is None else RunStatus(status)
        if final is RunStatus.RUNNING:
            raise ValueError("a run can only be set to a final status")
        ended = None if final is None else (time.time() if ended_at is None else ended_at)

        def write(conn: sqlite3.Connection) -> None:
            self._require_run(conn, run_id)
            if blobs:
                row = conn.execute("SELECT data FROM curves WHERE run_id = ?", (run_id,)).fetchone()
                stored = {} if row is None else unpack_curves(row[0])
                stored.update(blobs)
                conn.execute(
                    "INSERT OR REPLACE INTO curves (run_id, data) VALUES (?, ?)",
                    (run_id, pack_curves(dict(sorted(stored.items())))),
                )
            if figure_rows:
                row = conn.execute("SELECT figures FROM runs WHERE id = ?", (run_id,)).fetchone()
                merged = {f.name: f for f in _figures_from_json(row[0])}
                merged.update((f.name, f) for f in figure_rows)  # a known name keeps its place
                conn.execute(
                    "UPDATE runs SET figures = ? WHERE id = ?",
                    (_figures_to_json(merged.values()), run_id),
                )
            if agent_path is not None:
                conn.execute(
                    "UPDATE runs SET agent_path = ? WHERE id = ?", (str(agent_path), run_id)
                )
            if final is not None:
                conn.execute(
                    "UPDATE runs SET status = ?, ended_at = ? WHERE id = ?",
                    (str(final), ended, run_id),
                )

        self._write(write)

    def put_curves(
        self, run_id: int, curves: Iterable[Curve], max_points: int = STORED_POINTS
    ) -> None:
        """Add or replace curves of a run, each kept to at most `max_points` bucket means."""
        self.update(run_id, curves=curves, max_points=max_points)

    def put_figures(self, run_id: int, figures: Iterable[Figure]) -> None:
        """Add figures to a run, or replace those with the same name (keeping their place)."""
        self.update(run_id, figures=figures)

    def set_agent_path(self, run_id: int, path: str | Path | None) -> None:
        """Where the run's agent was saved (None: it has none)."""

        def write(conn: sqlite3.Connection) -> None:
            self._require_run(conn, run_id)
            value = None if path is None else str(path)
            conn.execute("UPDATE runs SET agent_path = ? WHERE id = ?", (value, run_id))

        self._write(write)

    def finish(
        self, run_id: int, status: RunStatus = RunStatus.FINISHED, ended_at: float | None = None
    ) -> None:
        """Mark a run finished, interrupted or failed, now or at `ended_at`."""
        self.update(run_id, status=status, ended_at=ended_at)

    # -- queries -------------------------------------------------------------

    def list_runs(
        self,
        *,
        game: str | None = None,
        kind: RunKind | str | None = None,
        limit: int | None = None,
    ) -> list[RunSummary]:
        """The runs, newest first; only those of `game` and `kind` when given."""
        sql = _SUMMARY_SELECT + " WHERE 1 = 1"
        args: list[Any] = []
        if game is not None:
            sql += " AND s.game = ? COLLATE NOCASE"
            args.append(game)
        if kind is not None:
            sql += " AND r.kind = ?"
            args.append(str(RunKind(kind)))
        sql += " ORDER BY r.started_at DESC, r.id DESC"
        if limit is not None:
            sql += " LIMIT ?"
            args.append(int(limit))
        with self._read() as conn:
            rows = conn.execute(sql, args).fetchall()
        with self._damaged_rows():
            return [_summary(row) for row in rows]

    def get_run(self, run_id: int) -> RunRecord:
        """Everything about one run; UnknownRunError if there is none with that id."""
        with self._read() as conn:
            row = conn.execute(_RECORD_SELECT, (run_id,)).fetchone()
            if row is None:
                raise UnknownRunError(f"no run {run_id} in {self.path}")
            blob = conn.execute("SELECT data FROM curves WHERE run_id = ?", (run_id,)).fetchone()
            stored = {} if blob is None else unpack_curves(blob[0])
            curves = tuple(Curve(name, *decode_curve(data)) for name, data in stored.items())
        with self._damaged_rows():
            game_params, wrappers, hyperparameters = (json.loads(text) for text in row[10:13])
            return RunRecord(
                summary=_summary(row),
                game_params=game_params,
                wrappers=tuple(WrapperSetting(w["name"], w["params"]) for w in wrappers),
                hyperparameters=hyperparameters,
                versions=Versions(*row[13:17]),
                curves=curves,
                agent_path=row[17],
            )

    def remove_run(self, run_id: int) -> RunSummary:
        """Delete a run with its curves and figures; what it was."""

        def write(conn: sqlite3.Connection) -> RunSummary:
            row = conn.execute(_SUMMARY_SELECT + " WHERE r.id = ?", (run_id,)).fetchone()
            if row is None:
                raise UnknownRunError(f"no run {run_id} in {self.path}")
            with self._damaged_rows():
                summary = _summary(row)
            ids = conn.execute(
                "SELECT settings_id, platform_id FROM runs WHERE id = ?", (run_id,)
            ).fetchone()
            conn.execute("DELETE FROM curves WHERE run_id = ?", (run_id,))
            conn.execute("DELETE FROM runs WHERE id = ?", (run_id,))
            # Settings and platforms no other run uses go with it.
            conn.execute(
                "DELETE FROM settings WHERE id = ? AND NOT EXISTS"
                " (SELECT 1 FROM runs WHERE settings_id = ?)",
                (ids[0], ids[0]),
            )
            conn.execute(
                "DELETE FROM platforms WHERE id = ? AND NOT EXISTS"
                " (SELECT 1 FROM runs WHERE platform_id = ?)",
                (ids[1], ids[1]),
            )
            return summary

        return self._write(write)


_SUMMARY_COLUMNS = (
    "r.id, r.kind, s.game, s.algorithm, r.seeds, r.status, r.started_at, r.ended_at,"
    " r.group_id, r.figures"
)
_SUMMARY_SELECT = f"SELECT {_SUMMARY_COLUMNS} FROM runs r JOIN settings s ON s.id = r.settings_id"
_RECORD_SELECT = (
    f"SELECT {_SUMMARY_COLUMNS}, s.game_params, s.wrappers, s.hyperparameters,"
    " p.tui_gym, p.gymnasium, p.numpy, p.python, r.agent_path"
    " FROM runs r JOIN settings s ON s.id = r.settings_id"
    " JOIN platforms p ON p.id = r.platform_id WHERE r.id = ?"
)


def _row_id(
    conn: sqlite3.Connection, table: str, columns: tuple[str, ...], values: tuple[str, ...]
) -> int:
    """The id of the row holding exactly `values`, inserted if there is none."""
    names = ", ".join(columns)
    marks = ", ".join("?" * len(columns))
    conn.execute(f"INSERT OR IGNORE INTO {table} ({names}) VALUES ({marks})", values)
    where = " AND ".join(f"{c} = ?" for c in columns)
    row = conn.execute(f"SELECT id FROM {table} WHERE {where}", values).fetchone()
    return int(row[0])


def _figures_to_json(figures: Iterable[Figure]) -> str:
    # SQLite and JSON have no NaN: a figure without a value is stored as null.
    return to_json_text(
        [[f.name, f.value if math.isfinite(f.value) else None, f.unit, f.ci95] for f in figures],
        "the figures",
    )


def _figures_from_json(text: str) -> tuple[Figure, ...]:
    return tuple(
        Figure(name, float("nan") if value is None else value, unit, ci95)
        for name, value, unit, ci95 in json.loads(text)
    )


def _summary(row: Sequence[Any]) -> RunSummary:
    run_id, kind, game, algorithm, seeds, status, started, ended, group, figures = row[:10]
    return RunSummary(
        id=run_id,
        kind=RunKind(kind),
        game=game,
        algorithm=algorithm,
        seeds=tuple(json.loads(seeds)),
        status=RunStatus(status),
        started_at=started,
        ended_at=ended,
        figures=_figures_from_json(figures),
        group=group,
    )
