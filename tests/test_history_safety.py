"""Files that are not our run history are refused in one line and left as they were;
the schema upgrades through its migrations and refuses a newer one."""

from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tui_gym.core.experiments import (
    Curve,
    DamagedRunHistoryError,
    NewerRunHistoryError,
    NotARunHistoryError,
    RunHistory,
    RunHistoryError,
    RunKind,
    RunSpec,
    list_runs,
)
from tui_gym.core.experiments.connection import APPLICATION_ID, MIGRATIONS, Migration


def spec(seed: int = 0) -> RunSpec:
    return RunSpec(kind=RunKind.TRAIN, game="blackjack", algorithm="q_learning", seeds=(seed,))


def files_beside(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.parent.iterdir()) if p.is_file()}


def refused(path: Path, error: type[RunHistoryError], *phrases: str) -> None:
    """Opening `path` raises `error` in one line naming it and the phrases; nothing changes."""
    before = path.read_bytes()
    with pytest.raises(error) as caught:
        RunHistory(path)
    message = str(caught.value)
    assert "\n" not in message
    assert str(path) in message
    for phrase in phrases:
        assert phrase in message
    assert path.read_bytes() == before
    # The commands that only read say the same.
    with pytest.raises(error):
        list_runs(str(path))
    assert path.read_bytes() == before


def test_random_bytes(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    path.write_bytes(np.random.default_rng(0).bytes(8192))
    refused(path, NotARunHistoryError, "not a tui-gym run history", "left untouched")
    assert [p.name for p in tmp_path.iterdir()] == ["runs.db"]


def test_text_file_and_truncated_header(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    path.write_text("episode,return\n1,0.5\n")
    refused(path, NotARunHistoryError, "not an SQLite database")
    path.write_bytes(b"SQLite for")
    refused(path, NotARunHistoryError, "not an SQLite database")


def test_sqlite_header_with_garbage_after_it(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    path.write_bytes(b"SQLite format 3\x00" + np.random.default_rng(1).bytes(4000))
    refused(path, NotARunHistoryError, "not a tui-gym run history")


def test_another_programs_database(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE contacts (name TEXT, phone TEXT)")
    conn.execute("INSERT INTO contacts VALUES ('Ada', '123')")
    conn.commit()
    conn.close()
    before = files_beside(path)
    refused(path, NotARunHistoryError, "another program", "contacts")
    assert files_beside(path) == before


def test_another_programs_empty_database_with_its_own_id(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA application_id = 1234")
    conn.commit()
    conn.close()
    refused(path, NotARunHistoryError, "another program", "1234")


def test_a_newer_schema_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        history.start_run(spec())
    conn = sqlite3.connect(path)
    conn.execute(f"PRAGMA user_version = {len(MIGRATIONS) + 1}")
    conn.commit()
    conn.close()
    refused(path, NewerRunHistoryError, "made by a newer tui-gym")


def test_a_damaged_history_of_ours(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        for seed in range(60):
            run_id = history.start_run(spec(seed))
            history.update(run_id, curves=[Curve.per_episode("return", np.zeros(500))])
    data = bytearray(path.read_bytes())
    assert len(data) > 5 * 4096
    data[2 * 4096 : 5 * 4096] = np.random.default_rng(2).bytes(3 * 4096)  # pages 3 to 5
    path.write_bytes(bytes(data))
    before = path.read_bytes()
    with pytest.raises(RunHistoryError) as caught, RunHistory(path) as history:
        for run in history.list_runs():
            history.get_run(run.id)
    message = str(caught.value)
    assert "\n" not in message and str(path) in message and "damaged" in message
    assert path.read_bytes() == before


def test_a_folder_is_refused(tmp_path: Path) -> None:
    with pytest.raises(NotARunHistoryError, match="is a folder"):
        RunHistory(tmp_path)


def test_an_empty_file_becomes_a_history(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    path.touch()
    with RunHistory(path) as history:
        assert history.list_runs() == []
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
    assert conn.execute("PRAGMA user_version").fetchone()[0] == len(MIGRATIONS)
    assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    conn.close()


def _add_note(conn: sqlite3.Connection) -> None:
    conn.execute("ALTER TABLE runs ADD COLUMN note TEXT NOT NULL DEFAULT ''")
    conn.execute("UPDATE runs SET note = 'from version 1'")


def test_migrations_upgrade_an_older_history_and_keep_its_runs(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        old_run = history.start_run(spec(7))
    now = len(MIGRATIONS)
    newer = (*MIGRATIONS, Migration(now + 1, "runs get a note", _add_note))
    with RunHistory(path, migrations=newer) as history:
        assert history.schema_version == now + 1
        assert [r.seeds for r in history.list_runs()] == [(7,)]
        assert history.start_run(spec(8)) > old_run  # the old code still writes what it knows
        notes = history._conn.execute("SELECT note FROM runs ORDER BY id").fetchall()
    assert notes == [("from version 1",), ("",)]
    conn = sqlite3.connect(path)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == now + 1
    conn.close()
    # Opening it again applies nothing twice; the code of the version before now refuses it.
    RunHistory(path, migrations=newer).close()
    refused(path, NewerRunHistoryError, "newer tui-gym", f"version {now + 1}", f"up to {now}")


def test_a_version_1_history_is_brought_up_to_date_with_its_runs(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    RunHistory(path, migrations=MIGRATIONS[:1]).close()
    with sqlite3.connect(path) as conn:  # a run as version 1 wrote it
        conn.execute("INSERT INTO platforms VALUES (1, '0.1.0', '1.0.0', '2.0.0', '3.11.0')")
        conn.execute("INSERT INTO settings VALUES (1, 'blackjack', '{}', '[]', 'q', '{}')")
        conn.execute("INSERT INTO runs (kind, settings_id, platform_id, seeds, status, started_at)"
                     " VALUES ('train', 1, 1, '[3]', 'running', 1.0)")
    conn.close()
    with RunHistory(path) as history:
        assert history.schema_version == len(MIGRATIONS)
        [run] = history.list_runs()
    # A run from before writers were marked cannot be told dead: it is taken at its word.
    assert run.seeds == (3,) and run.status == "running"


def test_a_failing_migration_changes_nothing(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        history.start_run(spec())

    def broken(conn: sqlite3.Connection) -> None:
        conn.execute("ALTER TABLE runs ADD COLUMN half_done TEXT")
        raise sqlite3.OperationalError("no such table: missing")

    with pytest.raises(RunHistoryError, match="no such table"):
        RunHistory(path, migrations=(*MIGRATIONS, Migration(len(MIGRATIONS) + 1, "broken", broken)))
    with RunHistory(path) as history:
        assert history.schema_version == len(MIGRATIONS) and len(history.list_runs()) == 1
        columns = [row[1] for row in history._conn.execute("PRAGMA table_info(runs)")]
    assert "half_done" not in columns


def test_migrations_must_be_numbered_in_order(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="out of order"):
        RunHistory(tmp_path / "runs.db",
                   migrations=(*MIGRATIONS, Migration(len(MIGRATIONS) + 2, "gap", _add_note)))
    assert not (tmp_path / "runs.db").exists()


def test_a_folder_that_cannot_be_made_is_one_line(tmp_path: Path) -> None:
    blocker = tmp_path / "data"
    blocker.write_text("a file where the folder should be")
    with pytest.raises(RunHistoryError) as caught:
        RunHistory(blocker / "tui-gym" / "runs.db")
    message = str(caught.value)
    assert "\n" not in message and "cannot create its folder" in message
    assert blocker.read_text() == "a file where the folder should be"


RECORD_ONE = (
    "import sys\n"
    "from tui_gym.core.experiments import RunHistory, RunSpec\n"
    "with RunHistory(sys.argv[1]) as history:\n"
    "    seeds = (int(sys.argv[2]),)\n"
    "    history.start_run(RunSpec('train', 'blackjack', 'q_learning', seeds=seeds))\n"
)


def test_looking_at_the_file_again_keeps_what_this_process_writes(tmp_path: Path) -> None:
    """Another look at the file from this process (the Compare view reading while the app
    records) must not cost the process its locks: else the next process to close the file
    takes itself for the last and removes the write-ahead log this process writes to, and
    what later processes record is lost when this one folds its log in."""
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        history.start_run(spec(0))  # closed: the runs are in the file itself now
    with RunHistory(path) as history:
        history.start_run(spec(1))
        RunHistory(path).close()
        for seeds in ((100, 2), (200, 3)):  # another process records and closes, then this one
            subprocess.run([sys.executable, "-c", RECORD_ONE, str(path), str(seeds[0])],
                           check=True, timeout=60)
            history.start_run(spec(seeds[1]))
    read = ("import sys, sqlite3; conn = sqlite3.connect(sys.argv[1]); "
            "print(*sorted(r[0] for r in conn.execute('SELECT seeds FROM runs')), "
            "conn.execute('PRAGMA integrity_check').fetchone()[0])")
    found = subprocess.run([sys.executable, "-c", read, str(path)], capture_output=True,
                           text=True, check=True, timeout=60).stdout.split()
    assert found == ["[0]", "[100]", "[1]", "[200]", "[2]", "[3]", "ok"]


def test_a_device_is_refused_and_nothing_is_made_beside_it(tmp_path: Path) -> None:
    before = set(Path("/dev").iterdir())
    for make in (RunHistory, lambda p: list_runs(str(p))):
        with pytest.raises(NotARunHistoryError) as caught:
            make(Path("/dev/null"))
        message = str(caught.value)
        assert "\n" not in message and "/dev/null is not a regular file" in message
    assert set(Path("/dev").iterdir()) == before  # no /dev/null-journal, -wal or -shm


def test_a_path_that_cannot_be_examined_is_one_line(tmp_path: Path) -> None:
    long_name = tmp_path / ("x" * 300) / "runs.db"
    for make in (RunHistory, lambda p: list_runs(str(p))):
        with pytest.raises(RunHistoryError) as caught:
            make(long_name)
        message = str(caught.value)
        assert "\n" not in message and "cannot be examined (File name too long)" in message
        assert len(message) < 300  # the name is cut to a readable length


@pytest.mark.skipif(os.geteuid() == 0, reason="permissions do not stop root")
def test_a_folder_without_permissions_is_one_line(tmp_path: Path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0)
    try:
        with pytest.raises(RunHistoryError, match="cannot be examined .Permission denied"):
            RunHistory(locked / "runs.db")
    finally:
        locked.chmod(0o700)


READ_ONLY_CHECK = """
import json, sys
from tui_gym.core.experiments import RunHistory, RunHistoryError, list_runs, show_run
path = sys.argv[1]
try:
    RunHistory(path)
    written = "opened for writing"
except RunHistoryError as exc:
    written = str(exc)
print(json.dumps({"runs": [r.id for r in list_runs(path).runs],
                  "curve": show_run(1, path).curve("return") is not None, "write": written}))
"""


def in_read_only_folder(folder: Path, code: str, *args: str) -> str:
    """What Python `code` prints with `folder` read-only: by its mode, or for root (whom
    modes do not stop) in a read-only bind mount of its own."""
    if os.geteuid() != 0:
        folder.chmod(0o555)
        try:
            return subprocess.run([sys.executable, "-c", code, *args], capture_output=True,
                                  text=True, check=True, timeout=60).stdout
        finally:
            folder.chmod(0o755)
    mount = (f"mount --bind '{folder}' '{folder}' && mount -o remount,bind,ro '{folder}' && "
             f"exec '{sys.executable}' -c \"$0\" \"$@\"")
    done = subprocess.run(["unshare", "-m", "sh", "-c", mount, code, *args],
                          capture_output=True, text=True, timeout=60)
    if done.returncode != 0 and ("mount" in done.stderr or "unshare" in done.stderr):
        pytest.skip(f"root, and no read-only mount here: {done.stderr.strip()}")
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_a_history_in_a_read_only_folder_can_be_listed_and_shown(tmp_path: Path) -> None:
    folder = tmp_path / "shared"
    path = folder / "runs.db"
    with RunHistory(path) as history:
        run_id = history.start_run(spec(4))
        history.update(run_id, curves=[Curve.per_episode("return", np.zeros(10))])
    found = json.loads(in_read_only_folder(folder, READ_ONLY_CHECK, str(path)))
    assert found["runs"] == [run_id] and found["curve"]
    assert "cannot be written" in found["write"] and "\n" not in found["write"]
    assert sorted(p.name for p in folder.iterdir()) == ["runs.db"]


def test_refusing_a_truncated_history_leaves_nothing_beside_it(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    with RunHistory(path) as history:
        for seed in range(60):
            run_id = history.start_run(spec(seed))
            history.update(run_id, curves=[Curve.per_episode("return", np.zeros(300))])
    data = path.read_bytes()
    for cut in (4096, 3 * 4096, len(data) // 2):
        path.write_bytes(data[:cut])
        for make in (RunHistory, lambda p: list_runs(str(p))):
            with pytest.raises(DamagedRunHistoryError) as caught:
                make(path)
            message = str(caught.value)
            assert "\n" not in message and "is damaged" in message
            assert f"tui-gym runs --recover --db {path}" in message
            assert [p.name for p in tmp_path.iterdir()] == ["runs.db"], cut
            assert path.read_bytes() == data[:cut]
