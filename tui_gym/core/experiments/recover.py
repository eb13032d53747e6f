"""Saving what can be read of a damaged run history: `recover`."""

from __future__ import annotations

import contextlib
import os
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tui_gym.core.experiments.rows as rows
from tui_gym.core.experiments.codec import BadTask, decode
from tui_gym.core.experiments.connection import WriterCheck, examine, shown
from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.figures import FieldsJson
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.records import RunStatus, TaskRecord
from tui_gym.core.text import visible

PROBE_BEYOND = 100_000  # ids asked for one by one past the last one a damaged scan found


@dataclass(frozen=True)
class Recovery(FieldsJson):
    """What `recover` did: the runs it copied from `source` into `target`, the runs it
    found but could not read, and SQLite's verdict on the source ("ok" when sound)."""

    source: Path
    target: Path | None  # None when nothing could be read
    copied: int
    unreadable: int
    curves_dropped: int  # runs copied without curves that did not decode
    check: str


def _fresh_path(source: Path) -> Path:
    """A name beside `source` that nothing has, made (empty) so no one else takes it."""
    for n in range(1, 1000):
        mark = "recovered" if n == 1 else f"recovered-{n}"
        target = source.with_name(f"{source.stem}.{mark}{source.suffix}")
        try:
            # A new, empty file: no connection has it open, so a plain handle is harmless.
            os.close(os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        except OSError as exc:
            raise RunHistoryError(f"cannot write beside {shown(source)} ({exc.strerror})") from None
        return target
    raise RunHistoryError(f"cannot find a free name beside {shown(source)}")


def _reader(source: Path) -> sqlite3.Connection:
    """A connection that only reads `source` and makes no file beside it (immutable without a
    write-ahead log), told to read past a page count the file no longer has."""
    wal = os.path.lexists(f"{source}-wal")
    uri = f"{source.resolve().as_uri()}?mode=ro{'' if wal else '&immutable=1'}"
    conn = sqlite3.connect(uri, uri=True, isolation_level=None)
    try:
        conn.execute("PRAGMA writable_schema = 1")  # changes nothing: the file is read only
        conn.execute("SELECT COUNT(*) FROM sqlite_master").fetchone()
    except sqlite3.Error as exc:
        conn.close()
        raise RunHistoryError(f"nothing can be read from {shown(source)} ({visible(exc, 80)})"
                              ) from None
    return conn


def _check(conn: sqlite3.Connection) -> str:
    try:
        found = [row[0] for row in conn.execute("PRAGMA quick_check(3)")]
    except sqlite3.Error as exc:
        return visible(exc, 120)
    lines = [part.strip() for text in found for part in str(text).splitlines() if part.strip()]
    return visible("; ".join(lines), 200)


def _scan(conn: sqlite3.Connection, order: str) -> tuple[list[int], bool]:
    """The run ids a scan reads before it stops; whether it read to the end."""
    ids: list[int] = []
    try:
        for (run_id,) in conn.execute(f"SELECT id FROM runs ORDER BY id {order}"):
            ids.append(int(run_id))
    except sqlite3.Error:
        return ids, False
    return ids, True


def _run_ids(conn: sqlite3.Connection) -> Iterator[int]:
    ids, whole = _scan(conn, "ASC")
    if whole:
        yield from ids
        return
    found = set(ids) | set(_scan(conn, "DESC")[0])
    try:
        top = conn.execute("SELECT seq FROM sqlite_sequence WHERE name = 'runs'").fetchone()
        last = int(top[0]) if top else 0
    except (sqlite3.Error, TypeError, ValueError):
        last = 0
    last = min(max([last, *found, 0]), max(found, default=0) + PROBE_BEYOND)
    yield from sorted(found | set(range(1, last + 1)))


def _fetch(conn: sqlite3.Connection, table: str, alias: str, key: object,
           have: set[str] | None = None) -> dict[str, Any] | None:
    """The FIELDS of `alias` from `table`'s row `key` (null for a column not in `have`), from
    runs with its settings and platform ids; None without such a row."""
    fields = [f for f in rows.FIELDS if f.startswith(alias)]
    columns = ", ".join(rows.column(f, alias=False) if have is None or f[2:] in have else "NULL"
                        for f in fields)
    if table == "runs":
        columns += ", settings_id, platform_id"
    row = conn.execute(f"SELECT {columns} FROM {table} WHERE id = ?", (key,)).fetchone()
    return None if row is None else dict(zip([*fields, "settings", "platform"], row, strict=False))


def _one(conn: sqlite3.Connection, have: set[str], run_id: int
         ) -> tuple[tuple[Any, ...], Any] | None:
    """A run's row, as `rows.record` reads it, and its curves; each table read on its own
    so that a damaged one loses only what it holds (a platform: the versions)."""
    run = _fetch(conn, "runs", "r.", run_id, have)
    if run is None:
        return None
    settings = _fetch(conn, "settings", "s.", run["settings"])
    if settings is None:
        raise rows.BadRow("its settings are gone")
    try:
        versions = _fetch(conn, "platforms", "p.", run["platform"])
    except sqlite3.Error:
        versions = None
    values = {**run, **settings, **(versions or {})}
    try:
        blob = conn.execute(f"SELECT {rows.CURVES_COLUMNS} FROM curves WHERE run_id = ?",
                            (run_id,)).fetchone()
    except sqlite3.Error:
        blob = ("damaged", 0, None)
    return (run_id, *(values.get(f, "") for f in rows.FIELDS)), blob


def _tasks(conn: sqlite3.Connection, run_id: int) -> list[TaskRecord]:
    """A run's finished tasks that read (none where their table is missing or damaged)."""
    try:
        found = conn.execute("SELECT inputs, returns, exact FROM tasks WHERE run_id = ?",
                             (run_id,)).fetchall()
    except sqlite3.Error:
        return []
    kept = []
    for row in found:
        with contextlib.suppress(BadTask):
            kept.append(decode(*row))
    return kept


def recover(source: str | Path) -> Recovery:
    """Copy what can be read of the history at `source` into a fresh file beside it."""
    source = Path(source).expanduser()
    if examine(source) is None:
        raise RunHistoryError(f"no run history at {shown(source)}")
    conn = _reader(source)
    try:
        check = _check(conn)
        target = _fresh_path(source)
        copied = unreadable = dropped = 0
        try:
            with RunHistory(target) as history:
                writers = WriterCheck()
                try:  # the runs table's columns (an older schema lacks some)
                    have = {row[1] for row in conn.execute("PRAGMA table_info(runs)")}
                except sqlite3.Error:
                    have = set()
                for run_id in _run_ids(conn):
                    try:
                        found = _one(conn, have, run_id)
                        if found is None:
                            continue  # no run with that id
                        row, blob = found
                        try:
                            curves = () if blob is None else rows.curves(*blob)
                        except rows.BadRow:
                            curves, dropped = (), dropped + 1
                        record = rows.record(row, curves, writers)
                    except (sqlite3.Error, rows.BadRow):
                        unreadable += 1
                        continue
                    alive = record.summary.status is RunStatus.RUNNING
                    history.restore_run(record, writer=row[10] if alive else None)
                    for task in _tasks(conn, run_id):
                        history.put_task(run_id, task)
                    copied += 1
        except BaseException:
            target.unlink(missing_ok=True)
            raise
        if not copied:
            target.unlink(missing_ok=True)
        return Recovery(source, target if copied else None, copied, unreadable, dropped, check)
    finally:
        conn.close()
