"""The run history's schema: migrations applied in order, the version in `PRAGMA user_version`."""

from __future__ import annotations

import sqlite3
from collections.abc import Callable, Sequence
from dataclasses import dataclass

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


def migrate(conn: sqlite3.Connection, current: int, migrations: Sequence[Migration]) -> int:
    """Apply the migrations after version `current` (inside the caller's transaction)."""
    latest = check_migrations(migrations)
    for migration in migrations[current:]:
        migration.apply(conn)
    if current < latest:
        conn.execute(f"PRAGMA user_version = {latest:d}")
        conn.execute(f"PRAGMA application_id = {APPLICATION_ID:d}")
    return latest
