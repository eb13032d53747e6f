"""Saving what can be read of a damaged run history: `recover`.

`recover(path)` reads the file through SQLite, for reading only, and copies
every run that still reads (its settings, figures, status and times, and its
curves when they decode) into a fresh history beside it,
`NAME.recovered.EXT` (`NAME.recovered-2.EXT`, ... when that exists), keeping
the run ids. The original is never written. Runs are found by a scan of the
runs table and, where the scan stops at damage, by asking for each id in turn.
"""

from __future__ import annotations

import os
import sqlite3
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tui_gym.core.experiments import rows
from tui_gym.core.experiments.connection import examine, shown
from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.records import RunStatus
from tui_gym.core.experiments.writers import WriterCheck
from tui_gym.core.text import visible

PROBE_BEYOND = 100_000  # ids asked for one by one past the last one a damaged scan found


@dataclass(frozen=True)
class Recovery:
    """What `recover` did: the runs it copied from `source` into `target`, the runs it
    found but could not read, and SQLite's verdict on the source ("ok" when sound)."""

    source: Path
    target: Path | None  # None when nothing could be read
    copied: int
    unreadable: int
    curves_dropped: int  # runs copied without curves that did not decode
    check: str

    def to_json(self) -> dict[str, Any]:
        return {
            "source": str(self.source),
            "target": None if self.target is None else str(self.target),
            "copied": self.copied,
            "unreadable": self.unreadable,
            "curves_dropped": self.curves_dropped,
            "check": self.check,
        }


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
    """A connection that only reads `source` (as a file nothing changes, where SQLite
    cannot read it otherwise: a read-only folder)."""
    uri = source.resolve().as_uri()
    problem: sqlite3.Error | None = None
    for mode in ("ro", "ro&immutable=1"):
        conn = sqlite3.connect(f"{uri}?mode={mode}", uri=True, isolation_level=None)
        try:
            conn.execute("SELECT COUNT(*) FROM sqlite_master").fetchone()
            return conn
        except sqlite3.Error as exc:
            problem = exc
            conn.close()
    raise RunHistoryError(f"nothing can be read from {shown(source)} ({visible(problem, 80)})")


def _check(conn: sqlite3.Connection) -> str:
    try:
        found = [row[0] for row in conn.execute("PRAGMA quick_check(3)")]
    except sqlite3.Error as exc:
        return visible(exc, 120)
    return "; ".join(visible(line, 80) for line in found)


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


def _one(conn: sqlite3.Connection, run_id: int) -> tuple[Any, Any] | None:
    try:
        row = conn.execute(
            f"SELECT {rows.RECORD_COLUMNS} {rows.RECORD_FROM} WHERE r.id = ?", (run_id,)
        ).fetchone()
    except sqlite3.Error:
        return None
    try:
        blob = conn.execute(
            f"SELECT {rows.CURVES_COLUMNS} FROM curves WHERE run_id = ?", (run_id,)
        ).fetchone()
    except sqlite3.Error:
        blob = ("damaged", 0, None)
    return row, blob


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
                for run_id in _run_ids(conn):
                    found = _one(conn, run_id)
                    if found is None:
                        unreadable += 1
                        continue
                    row, blob = found
                    if row is None:
                        continue  # no run with that id
                    try:
                        curves = () if blob is None else rows.curves(*blob)
                    except rows.BadRow:
                        curves, dropped = (), dropped + 1
                    try:
                        record = rows.record(row, curves, writers)
                    except rows.BadRow:
                        unreadable += 1
                        continue
                    alive = record.summary.status is RunStatus.RUNNING
                    history.restore_run(record, writer=row[10] if alive else None)
                    copied += 1
        except BaseException:
            target.unlink(missing_ok=True)
            raise
        if not copied:
            target.unlink(missing_ok=True)
        return Recovery(source, target if copied else None, copied, unreadable, dropped, check)
    finally:
        conn.close()
