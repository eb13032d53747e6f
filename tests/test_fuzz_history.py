"""Fuzz: run history rows. Every edit of a good history's rows (a field set to a nasty
value, a blob spoiled) leaves each run either read soundly or named in one line, the
others readable, and `runs`, `runs show` and `runs rm` without a traceback or a control
character; seeded, so every run tries the same edits."""

from __future__ import annotations

import contextlib
import json
import math
import random
import shutil
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import (
    Curve,
    DamagedRunError,
    Figure,
    RunHistory,
    RunRecord,
    RunSpec,
    RunStatus,
    WrapperSetting,
)
from tui_gym.core.experiments.codec import pack_curves, unpack_curves
from tui_gym.ui.compare_series import row_of_record, series_of_record
from tui_gym.ui.compare_view import describe_run

from .test_fuzz_params import nasty_text, nasty_value
from .test_history_rows import uvarint, zlib_bomb

SEED = 21
CASES = 120
CLI_CASES = 20
FIELDS = {
    "runs": ("kind", "settings_id", "platform_id", "seeds", "status", "started_at", "ended_at",
             "agent_path", "group_id", "figures", "writer"),
    "settings": ("game", "game_params", "wrappers", "algorithm", "hyperparameters"),
    "platforms": ("tui_gym", "gymnasium", "numpy", "python"),
    "curves": ("data",),
}


@pytest.fixture(scope="module")
def template(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A good history: four runs of several kinds, each with settings, curves and figures."""
    path = tmp_path_factory.mktemp("fuzz-history") / "runs.db"
    rng = np.random.default_rng(SEED)
    with RunHistory(path) as history:
        for i, (kind, game, algorithm) in enumerate((
            ("train", "blackjack", "q-learning"), ("compare", "gridworld", "sarsa"),
            ("app", "frozenlake", "expected-sarsa"), ("sweep", "taxi", "double-q"),
        )):
            run_id = history.start_run(RunSpec(
                kind, game, algorithm, game_params={"size": 4 + i},
                wrappers=(WrapperSetting("TimeLimit", {"max_episode_steps": 50 + i}),),
                hyperparameters={"learning_rate": 0.1 * (i + 1), "episodes": 1000},
                seeds=range(i + 1),
            ))
            history.update(
                run_id,
                curves=[Curve.per_episode("return", rng.normal(size=300)),
                        Curve("exact_value", [0, 100, 250], [0.1, np.nan, 0.3])],
                figures=[Figure("mean_return_last", -0.25, "return", 0.01), Figure("x", 2.0)],
                agent_path=f"/tmp/agent-{i}.tgym", status=RunStatus.FINISHED,
            )
    return path


def nasty_json(rng: random.Random) -> str:
    kind = rng.randrange(5)
    if kind == 0:
        depth = rng.choice([20, 1000, 100_000])
        return "[" * depth + "]" * depth
    if kind == 1:
        return "".join(rng.choice('[]{}",:0123456789.eE-+ abtrufnlsNI') for _ in range(30))
    if kind == 2:
        return rng.choice(["NaN", "Infinity", "-Infinity", "null", "true", "1e999", "{}", "[]",
                           '[["a"]]', '[["a", 1, "", 2, 3]]', '[[1, 2, 3, 4]]', '{"a": NaN}'])
    try:
        return json.dumps(nasty_value(rng))
    except (ValueError, RecursionError):
        return "[]"


def spoiled_blob(rng: random.Random, blob: bytes) -> bytes:
    kind = rng.randrange(5)
    if kind == 0:  # bits flipped
        data = bytearray(blob)
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        return bytes(data)
    if kind == 1:  # cut short or padded
        cut = rng.randrange(len(blob))
        return blob[:cut] if rng.random() < 0.5 else blob + bytes(rng.randrange(256)
                                                                 for _ in range(cut % 32))
    if kind == 2:  # a curve that claims more points than it holds
        n = rng.choice([2**20, 300_000_000, 2**62])
        return pack_curves({"return": bytes([1]) + uvarint(n) + bytes([0, 1, 0, 0, 0])})
    if kind == 3:  # episodes that inflate far past what their points need
        return zlib_bomb(rng.choice([1, 4, 100]), rng.choice([10_000, 2_000_000]))
    curves = unpack_curves(blob)  # a name of bytes that are not text, or a curve swapped
    name = rng.choice(list(curves))
    curves[name] = bytes(rng.randrange(256) for _ in range(rng.randint(0, 40)))
    return pack_curves(curves)


def nasty_field(rng: random.Random, table: str, column: str, current: Any) -> Any:
    kind = rng.randrange(6)
    if table == "curves" and isinstance(current, bytes) and kind < 3:
        return spoiled_blob(rng, current)
    if kind == 0:
        return nasty_json(rng)
    if kind == 1:
        return nasty_text(rng)
    if kind == 2:
        return rng.choice([None, 0, -1, 2**63 - 1, 1e300, -1e300, 0.5, math.pi])
    if kind == 3:
        return rng.choice([b"", b"\x00\xff", bytes(range(256)), "x" * 300_000])
    if kind == 4:
        return str(rng.choice([1e300, -5, 3.5, "abc", 2**70]))
    return rng.choice(["q\x1b]2;PWNED\x1b\\", "\x1b[2J", "[/bold]", "\u202e", "", " "])


def mutate(rng: random.Random, path: Path) -> None:
    """One to three edits of random fields of random rows, made behind tui-gym's back."""
    conn = sqlite3.connect(path)
    with conn:
        for _ in range(rng.randint(1, 3)):
            table = rng.choice(list(FIELDS))
            column = rng.choice(FIELDS[table])
            rowids = [r[0] for r in conn.execute(f"SELECT rowid FROM {table}")]
            if not rowids:
                continue
            rowid = rng.choice(rowids)
            current = conn.execute(f"SELECT {column} FROM {table} WHERE rowid = ?",
                                   (rowid,)).fetchone()[0]
            value = nasty_field(rng, table, column, current)
            # A NOT NULL, or a number SQLite cannot hold: that edit does not happen.
            with contextlib.suppress(sqlite3.IntegrityError, OverflowError):
                conn.execute(f"UPDATE {table} SET {column} = ? WHERE rowid = ?", (value, rowid))
    conn.close()


def check_record(record: RunRecord) -> None:
    """A run that read must be sound enough to show, draw and write as JSON."""
    json.dumps(record.to_json(), allow_nan=True)
    describe_run(record.summary)
    row_of_record(record)
    series_of_record(record)
    for curve in record.curves:
        assert len(curve) < 10_000 and not np.isinf(curve.values).any()


def test_every_edited_history_reads_each_run_or_names_it(template: Path, tmp_path: Path) -> None:
    rng = random.Random(SEED)
    named = 0
    for case in range(CASES):
        path = tmp_path / f"case-{case}.db"
        shutil.copy(template, path)
        mutate(rng, path)
        with RunHistory(path) as history:
            found = history.read_runs()
            ids = {r.id for r in found.runs} | {d.id for d in found.damaged}
            assert ids == {1, 2, 3, 4}, case
            for run_id in sorted(ids):
                try:
                    check_record(history.get_run(run_id))
                except DamagedRunError as exc:
                    message = str(exc)
                    assert message.startswith(f"run {run_id} in "), message
                    assert "\n" not in message and "\x1b" not in message, message
                    assert len(message) < 400 + len(str(path)), message
                    named += 1
            history.remove_run(rng.choice(sorted(ids)))
            left = history.read_runs()
            assert len(left.runs) + len(left.damaged) == 3
    assert named > CASES // 3  # the edits do damage


def test_the_commands_answer_edited_histories_in_one_line(
    template: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rng = random.Random(SEED + 1)
    for case in range(CLI_CASES):
        path = tmp_path / f"case-{case}.db"
        shutil.copy(template, path)
        mutate(rng, path)
        for argv in (["runs"], ["runs", "--json"], ["runs", "show", str(rng.randint(1, 4))],
                     ["runs", "rm", str(rng.randint(1, 4))]):
            code = main([*argv, "--db", str(path)])
            out, err = capsys.readouterr()
            assert code in (0, 2), (case, argv)
            assert "Traceback" not in out + err and "\x1b" not in out + err, (case, argv)
            if code == 2:
                assert out == "" and err.count("\n") == 1, (case, argv, err)
