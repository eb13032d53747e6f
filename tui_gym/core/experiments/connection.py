"""The one SQLite connection a process keeps to a run history file (`open_shared`), the
file's schema migrations, and which process records a run and whether it is still there."""

from __future__ import annotations

import contextlib
import os
import socket
import sqlite3
import stat
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TypeVar

from tui_gym.core.experiments.errors import (
    DamagedRunHistoryError,
    NewerRunHistoryError,
    NotARunHistoryError,
    RunHistoryBusyError,
    RunHistoryError,
)
from tui_gym.core.files import pid_alive
from tui_gym.core.text import visible

T = TypeVar("T")

SIDE_FILES = ("-wal", "-shm", "-journal")
_READ_ONLY = frozenset({"SQLITE_READONLY", "SQLITE_CANTOPEN", "SQLITE_PERM", "SQLITE_AUTH"})

APPLICATION_ID = 0x54475944  # "TGYD": marks a tui-gym run history


@dataclass(frozen=True)
class Migration:
    """The step to schema version `version` (from version - 1)."""

    version: int
    description: str
    apply: Callable[[sqlite3.Connection], None]


def _statements(*sql: str) -> Callable[[sqlite3.Connection], None]:
    def apply(conn: sqlite3.Connection) -> None:
        for statement in sql:
            conn.execute(statement)

    return apply


_V1 = _statements(
    """CREATE TABLE platforms (
        id INTEGER PRIMARY KEY,
        tui_gym TEXT NOT NULL,
        gymnasium TEXT NOT NULL,
        numpy TEXT NOT NULL,
        python TEXT NOT NULL,
        UNIQUE (tui_gym, gymnasium, numpy, python)
    )""",
    """CREATE TABLE settings (
        id INTEGER PRIMARY KEY,
        game TEXT NOT NULL,
        game_params TEXT NOT NULL,
        wrappers TEXT NOT NULL,
        algorithm TEXT NOT NULL,
        hyperparameters TEXT NOT NULL,
        UNIQUE (game, game_params, wrappers, algorithm, hyperparameters)
    )""",
    # AUTOINCREMENT: a removed run's id is never given to a later run.
    """CREATE TABLE runs (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        kind TEXT NOT NULL,
        settings_id INTEGER NOT NULL REFERENCES settings(id),
        platform_id INTEGER NOT NULL REFERENCES platforms(id),
        seeds TEXT NOT NULL,
        status TEXT NOT NULL,
        started_at REAL NOT NULL,
        ended_at REAL,
        agent_path TEXT,
        group_id INTEGER,
        figures TEXT NOT NULL DEFAULT '[]'
    )""",
    """CREATE TABLE curves (
        run_id INTEGER PRIMARY KEY REFERENCES runs(id) ON DELETE CASCADE,
        data BLOB NOT NULL
    )""",
)

_V2 = _statements(
    "ALTER TABLE runs ADD COLUMN writer TEXT",
    "CREATE INDEX runs_by_start ON runs (started_at, id)",
)

_V3 = _statements(
    """CREATE TABLE tasks (
        run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
        first_row INTEGER NOT NULL,
        inputs TEXT NOT NULL,
        returns BLOB NOT NULL,
        exact BLOB,
        finished_at REAL NOT NULL,
        PRIMARY KEY (run_id, first_row)
    )""",
)

MIGRATIONS: tuple[Migration, ...] = (
    Migration(1, "runs, their settings and curves", _V1),
    Migration(2, "the process writing each run; runs indexed by start", _V2),
    Migration(3, "each finished task of a run, with its inputs", _V3),
)


def check_migrations(migrations: Sequence[Migration]) -> int:
    """The version `migrations` lead to; ValueError unless they are numbered 1, 2, ... in order."""
    for expected, migration in enumerate(migrations, start=1):
        if migration.version != expected:
            raise ValueError(f"migration {migration.version} is out of order (expected {expected})")
    return len(migrations)


def shown(path: str | Path) -> str:
    """A file's name as messages show it (control characters escaped, a long one cut)."""
    return visible(str(path), 160)


def _code(exc: sqlite3.Error) -> str:
    """SQLite's primary error name ("SQLITE_READONLY" for SQLITE_READONLY_DIRECTORY)."""
    return "_".join((getattr(exc, "sqlite_errorname", "") or "").split("_")[:2])


def is_damage(exc: sqlite3.Error) -> bool:
    return _code(exc) in ("SQLITE_CORRUPT", "SQLITE_NOTADB") or "malformed" in str(exc).lower()


def damaged(path: Path, what: object) -> DamagedRunHistoryError:
    """The error for a damaged file: what SQLite says, and how to save what it still holds."""
    return DamagedRunHistoryError(
        f"{shown(path)} is damaged ({visible(what, 120)}): `tui-gym runs --recover --db "
        f"{shown(path)}` copies what can still be read into a new file beside it"
    )


def untouched(path: Path, what: str) -> NotARunHistoryError:
    return NotARunHistoryError(
        f"{shown(path)} is not a tui-gym run history ({what}); it was left untouched"
    )


def examine(path: Path) -> os.stat_result | None:
    """The file's status (None when there is none yet); RunHistoryError for anything that
    is not a regular file, or a path that cannot be looked at."""
    try:
        status = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except (OSError, ValueError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise RunHistoryError(f"{shown(path)} cannot be examined ({why})") from None
    if stat.S_ISDIR(status.st_mode):
        raise NotARunHistoryError(f"{shown(path)} is a folder, not a run history file")
    if not stat.S_ISREG(status.st_mode):
        raise NotARunHistoryError(
            f"{shown(path)} is not a regular file (a device, a pipe or a socket): "
            "give a file's path with --db"
        )
    return status


def inspect(conn: sqlite3.Connection) -> tuple[int, int, list[str]]:
    """(application id, schema version, tables) of the file, inside the caller's transaction."""
    app_id = conn.execute("PRAGMA application_id").fetchone()[0]
    version = conn.execute("PRAGMA user_version").fetchone()[0]
    query = "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
    return app_id, version, [row[0] for row in conn.execute(query)]


def check_identity(path: Path, latest: int, app_id: int, version: int, tables: list[str]) -> int:
    """The file's schema version, 0 for an empty database; raises for anything not ours."""
    if app_id == APPLICATION_ID:
        if version > latest:
            raise NewerRunHistoryError(
                f"{shown(path)} was made by a newer tui-gym (run history version {version}; "
                f"this tui-gym reads up to {latest}): upgrade tui-gym, "
                "or record elsewhere with --db PATH"
            )
        return int(version)
    if app_id == 0 and version == 0 and not tables:
        return 0
    if tables:
        names = ", ".join(visible(t, 40) for t in tables[:3]) + (", ..." if len(tables) > 3 else "")
        raise untouched(path, f"an SQLite database of another program, with tables {names}")
    raise untouched(path, f"an SQLite database of another program (application id {app_id})")


class Connection:
    """One SQLite connection of this process, and the lock each thread takes to use it."""

    def __init__(self, key: tuple[int, str], conn: sqlite3.Connection, writable: bool) -> None:
        self.key = key
        self.conn = conn
        self.writable = writable
        self.version = 0  # the file's schema version
        self.users = 0
        self.lock = threading.Lock()

    def attempt(self, action: Callable[[sqlite3.Connection], T], timeout: float, path: Path,
                begin: str | None = "BEGIN") -> T:
        """`action(conn)` inside `begin` ... COMMIT (no transaction when None), tried again
        while another process holds the file `path`, for up to `timeout` seconds."""
        deadline = time.monotonic() + timeout
        pause = 0.001
        while True:
            with self.lock:
                try:
                    return self._once(action, begin)
                except sqlite3.OperationalError as exc:
                    text = str(exc).lower()
                    if not (_code(exc) in ("SQLITE_BUSY", "SQLITE_LOCKED") or "locked" in text
                            or "busy" in text):
                        raise
            if time.monotonic() >= deadline:
                raise RunHistoryBusyError(f"{shown(path)} is busy: another process kept it "
                                          f"locked for over {timeout:.0f} s")
            # The lock is free meanwhile: this process's other threads go on reading.
            time.sleep(pause)
            pause = min(2 * pause, 0.05)

    def _once(self, action: Callable[[sqlite3.Connection], T], begin: str | None) -> T:
        conn = self.conn
        if begin is None:
            return action(conn)
        conn.execute(begin)
        try:
            result = action(conn)
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise
        return result


_shared: dict[tuple[int, str], Connection] = {}
_shared_lock = threading.Lock()


def open_shared(path: Path, migrations: Sequence[Migration], timeout: float, *,
                read_only: bool = False) -> Connection:
    """This process's connection to `path` (opened if need be: created, made WAL, migrated;
    `read_only`: never created, read where it cannot be written); RunHistoryError else."""
    key = (os.getpid(), os.path.realpath(path))
    with _shared_lock:
        shared = _shared.get(key)
        if shared is not None and (shared.writable or read_only):
            if shared.version > len(migrations):  # opened by code that knows more versions
                check_identity(path, len(migrations), APPLICATION_ID, shared.version, [])
            if shared.version < len(migrations) and shared.writable:
                _upgrade(path, shared, migrations, timeout)
        else:
            shared = _connect(path, key, migrations, timeout, read_only)
            _shared[key] = shared
        shared.users += 1
        return shared


def release(shared: Connection) -> None:
    """One user fewer; the last one closes the connection."""
    with _shared_lock:
        shared.users -= 1
        if shared.users > 0:
            return
        if _shared.get(shared.key) is shared:
            del _shared[shared.key]
    with shared.lock:
        shared.conn.close()


class _ReadOnly(Exception):
    """The file can at most be read (a read-only file or folder)."""


def _connect(path: Path, key: tuple[int, str], migrations: Sequence[Migration], timeout: float,
             read_only: bool) -> Connection:
    status = examine(path)
    real = Path(key[1])
    if status is None:
        if read_only:
            raise RunHistoryError(f"{shown(path)}: there is no run history there yet")
        try:
            real.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RunHistoryError(
                f"{shown(path)}: cannot create its folder ({exc.strerror or exc})"
            ) from None
    before = {suffix for suffix in SIDE_FILES if os.path.lexists(f"{real}{suffix}")}
    try:
        try:
            return _open(path, real, key, "rw" if status else "rwc", migrations, timeout)
        except _ReadOnly as exc:
            if not read_only:
                raise RunHistoryError(f"{shown(path)} cannot be written ({exc})") from None
        # Only reading: open it for reading, or, with no write-ahead log to read, as a file
        # that does not change (SQLite then needs no -shm file beside it).
        mode = "ro" if os.path.lexists(f"{real}-wal") else "ro&immutable=1"
        try:
            return _open(path, real, key, mode, migrations, timeout)
        except _ReadOnly as exc:
            raise RunHistoryError(f"{shown(path)} cannot be read ({exc})") from None
    except (NotARunHistoryError, DamagedRunHistoryError):
        _tidy(real, before)
        raise


def _open(path: Path, real: Path, key: tuple[int, str], mode: str,
          migrations: Sequence[Migration], timeout: float) -> Connection:
    try:
        conn = sqlite3.connect(f"{real.as_uri()}?mode={mode}", uri=True, timeout=0,
                               isolation_level=None, check_same_thread=False)
    except sqlite3.Error as exc:
        if _code(exc) in _READ_ONLY:
            raise _ReadOnly(str(exc)) from None
        raise RunHistoryError(f"{shown(path)}: cannot open it ({exc})") from None
    shared = Connection(key, conn, writable=not mode.startswith("ro"))
    try:
        try:
            identity = shared.attempt(inspect, timeout, path)  # reading only, so far
            shared.version = check_identity(path, len(migrations), *identity)
            if shared.writable:
                conn.execute("PRAGMA synchronous = NORMAL")  # WAL stays consistent on a crash
                conn.execute("PRAGMA foreign_keys = ON")
                shared.attempt(lambda c: c.execute("PRAGMA journal_mode = WAL").fetchone(),
                               timeout, path, begin=None)
        except sqlite3.DatabaseError as exc:
            if _code(exc) == "SQLITE_NOTADB":
                raise untouched(path, "not an SQLite database") from None
            if shared.writable and _code(exc) in _READ_ONLY:
                raise _ReadOnly(str(exc)) from None
            if is_damage(exc):
                raise damaged(path, exc) from None
            raise RunHistoryError(f"{shown(path)}: cannot open it ({exc})") from None
        if shared.version < len(migrations):
            if not shared.writable:
                raise RunHistoryError(
                    f"{shown(path)} was made by an older tui-gym and cannot be brought up to "
                    "date where it is (it cannot be written there)"
                )
            _upgrade(path, shared, migrations, timeout)
    except BaseException:
        conn.close()
        raise
    return shared


def _upgrade(path: Path, shared: Connection, migrations: Sequence[Migration],
             timeout: float) -> None:
    latest = len(migrations)

    def upgrade(conn: sqlite3.Connection) -> int:
        # Another process may have got there first: look again under the write lock.
        current = check_identity(path, latest, *inspect(conn))
        for migration in migrations[current:]:
            migration.apply(conn)
        if current < latest:
            conn.execute(f"PRAGMA user_version = {latest:d}")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID:d}")
        return latest

    try:
        shared.version = shared.attempt(upgrade, timeout, path, begin="BEGIN IMMEDIATE")
    except sqlite3.DatabaseError as exc:
        if is_damage(exc):
            raise damaged(path, exc) from None
        raise RunHistoryError(f"{shown(path)}: cannot bring it up to date ({exc})") from None


def _tidy(real: Path, before: set[str]) -> None:
    """Remove the empty side files SQLite made beside a file that was refused."""
    made = [s for s in SIDE_FILES if s not in before and os.path.lexists(f"{real}{s}")]
    for suffix in made:
        if suffix != "-shm" and os.path.getsize(f"{real}{suffix}") > 0:
            return  # something was written there: not ours to remove
    for suffix in made:
        with contextlib.suppress(OSError):
            os.unlink(f"{real}{suffix}")


_PROC = "/proc"


def _read(path: str) -> str:
    try:
        with open(path, encoding="ascii", errors="replace") as fh:
            return fh.read(4096)
    except OSError:
        return ""


def _start_ticks(pid: int) -> str:
    """A process's start time in clock ticks since boot ("" where /proc has none)."""
    stat = _read(f"{_PROC}/{pid}/stat")
    # The command name (field 2) may hold spaces and parentheses: count after the last ")".
    fields = stat.rpartition(")")[2].split()
    return fields[19] if len(fields) > 19 else ""


@cache
def _boot() -> str:
    return _read(f"{_PROC}/sys/kernel/random/boot_id").strip()


def current_writer() -> str:
    """This process's mark: "host boot pid start" (boot and start empty where unknown)."""
    pid = os.getpid()
    return f"{socket.gethostname()} {_boot()} {pid} {_start_ticks(pid)}"


class WriterCheck:
    """Tells whether the writer of a run is gone; remembers each answer for one listing."""

    def __init__(self) -> None:
        self._host = socket.gethostname()
        self._boot = _boot()
        self._answers: dict[str, bool] = {}

    def gone(self, mark: object) -> bool:
        """Whether the process that wrote `mark` has ended (False when it cannot be told)."""
        if not isinstance(mark, str) or not mark:
            return False
        if mark not in self._answers:
            self._answers[mark] = self._gone(mark)
        return self._answers[mark]

    def _gone(self, mark: str) -> bool:
        parts = mark.split(" ")
        if len(parts) != 4 or parts[0] != self._host or not parts[2].isdigit():
            return False
        boot, pid, start = parts[1], int(parts[2]), parts[3]
        if boot and self._boot and boot != self._boot:
            return True  # written before the machine restarted
        if not pid_alive(pid):
            return True
        return bool(start) and _start_ticks(pid) not in ("", start)
