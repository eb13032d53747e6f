"""One edited or damaged row in a good history: that run is one line naming it, wherever it
is read (`runs`, `runs show`, `runs export`, `runs rm`); the other runs stay readable; no
field is ever read whole when it is oversized, and text from the history reaches the
terminal as data."""

from __future__ import annotations

import json
import sqlite3
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import (
    Curve,
    DamagedRunError,
    Figure,
    RunHistory,
    RunKind,
    RunSpec,
    RunStatus,
    list_runs,
    remove_run,
    show_run,
)
from tui_gym.core.experiments.codec import pack_curves


def record_three(db: Path) -> list[int]:
    """Three finished runs, each with its own settings, a curve and figures."""
    ids = []
    with RunHistory(db) as history:
        for seed in range(3):
            run_id = history.start_run(RunSpec(
                RunKind.TRAIN, "blackjack", "q-learning", seeds=(seed,),
                hyperparameters={"learning_rate": 0.01 * (seed + 1)},
            ))
            history.update(run_id, curves=[Curve.per_episode("return", np.linspace(-1, 0, 50))],
                           figures=[Figure("mean_return_last", -0.1, "return")],
                           status=RunStatus.FINISHED)
            ids.append(run_id)
    return ids


def edit(db: Path, sql: str, *args: object) -> None:
    """A change made behind tui-gym's back (an edit, a damaged write)."""
    conn = sqlite3.connect(db)
    with conn:
        conn.execute(sql, args)
    conn.close()


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def uvarint(value: int) -> bytes:
    out = bytearray()
    while True:
        byte, value = value & 0x7F, value >> 7
        out.append(byte | (0x80 if value else 0))
        if not value:
            return bytes(out)


# A curve blob of 10 bytes that claims 300,000,000 points.
HUGE_CLAIM = pack_curves({"return": bytes([1]) + uvarint(300_000_000) + bytes([0, 1, 2, 0, 0])})


def zlib_bomb(points: int = 10, inflated: int = 30_000_000) -> bytes:
    """A curve of `points` points whose episodes inflate to `inflated` bytes."""
    body = zlib.compress(b"\x01" * inflated, 9)
    curve = bytes([1]) + uvarint(points) + bytes([1]) + uvarint(len(body)) + body
    return pack_curves({"return": curve + b"\x00\x00" + b"\x00\x3c" * points})


# Edits that spoil what a listing reads: the run is named beside the listed ones.
IN_THE_LISTING = {
    "a 400-digit figure": ("UPDATE runs SET figures = ? WHERE id = 2",
                           f'[["mean_return_last", 1{"0" * 400}, "return", null]]'),
    "100k-deep JSON": ("UPDATE runs SET figures = ? WHERE id = 2",
                       "[" * 100_000 + "]" * 100_000),
    "started_at = 'abc'": ("UPDATE runs SET started_at = ? WHERE id = 2", "abc"),
    "started_at = 1e300": ("UPDATE runs SET started_at = ? WHERE id = 2", 1e300),
    "an unknown status": ("UPDATE runs SET status = ? WHERE id = 2", "\x1b]2;PWNED\x1b\\"),
    "seeds that are text": ("UPDATE runs SET seeds = ? WHERE id = 2", '"0"'),
    "its settings gone": ("UPDATE runs SET settings_id = ? WHERE id = 2", 999),
    "a figure of NaN": ("UPDATE runs SET figures = ? WHERE id = 2", '[["x", NaN, "", null]]'),
}
# Edits that spoil what only `show` and `export` read.
IN_THE_RECORD = {
    "hyperparameters = 'null'": ("UPDATE settings SET hyperparameters = ? WHERE id = "
                                 "(SELECT settings_id FROM runs WHERE id = 2)", "null"),
    "a curve blob as text": ("UPDATE curves SET data = ? WHERE run_id = 2", "not a blob"),
    "10 bytes claiming 300,000,000 points": ("UPDATE curves SET data = ? WHERE run_id = 2",
                                             HUGE_CLAIM),
    "a zlib body inflating to 30 MB": ("UPDATE curves SET data = ? WHERE run_id = 2",
                                       zlib_bomb()),
    "wrappers that are not a list": ("UPDATE settings SET wrappers = ? WHERE id = "
                                     "(SELECT settings_id FROM runs WHERE id = 2)", '{"a": 1}'),
}


@pytest.mark.parametrize("damage", list(IN_THE_LISTING))
def test_a_run_the_listing_cannot_read_is_named_and_the_others_listed(
    damage: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    record_three(db)
    edit(db, *IN_THE_LISTING[damage])
    listing = list_runs(str(db))
    assert [r.id for r in listing.runs] == [3, 1]
    assert [d.id for d in listing.damaged] == [2] and listing.total == 3

    code, out, err = run_cli(capsys, "runs", "--db", str(db))
    assert code == 0 and "Traceback" not in out + err
    assert err.count("\n") == 1 and err.startswith("tui-gym: run 2 cannot be read: ")
    assert "runs rm 2" in err and "\x1b" not in out + err and len(err) < 400
    code, out, err = run_cli(capsys, "runs", "--db", str(db), "--json")
    assert code == 0 and [d["id"] for d in json.loads(out)["damaged"]] == [2]
    the_record_is_one_line(capsys, db, tmp_path)


@pytest.mark.parametrize("damage", list(IN_THE_RECORD))
def test_a_run_whose_record_cannot_be_read_is_one_line(
    damage: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    record_three(db)
    edit(db, *IN_THE_RECORD[damage])
    assert [r.id for r in list_runs(str(db)).runs] == [3, 2, 1]
    tracemalloc.start()
    try:
        with pytest.raises(DamagedRunError, match="^run 2 in .* cannot be read: ") as caught:
            show_run(2, str(db))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert caught.value.run_id == 2
    assert peak < 20_000_000, f"refusing the run took {peak:,} bytes"  # nothing allocated whole
    the_record_is_one_line(capsys, db, tmp_path)


def the_record_is_one_line(capsys: pytest.CaptureFixture[str], db: Path, tmp_path: Path) -> None:
    """`show` and `export` of run 2 say one line; the others read; `rm` removes it."""
    for argv in (("runs", "show", "2"), ("runs", "export", "2", "--csv", str(tmp_path / "x.csv"))):
        code, out, err = run_cli(capsys, *argv, "--db", str(db))
        assert (code, out) == (2, ""), argv
        assert err.count("\n") == 1 and "run 2 in" in err and "cannot be read" in err, err
        assert "Traceback" not in err and "\x1b" not in err
    assert not (tmp_path / "x.csv").exists()
    for other in (1, 3):
        assert show_run(other, str(db)).curve("return") is not None
    code, out, err = run_cli(capsys, "runs", "rm", "2", "--db", str(db))
    assert code == 0 and out.startswith("removed run 2 (") and err == ""
    assert [r.id for r in list_runs(str(db)).runs] == [3, 1]
    assert list_runs(str(db)).damaged == ()


def test_remove_run_of_a_damaged_row_says_it_could_not_be_read(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    record_three(db)
    edit(db, "UPDATE runs SET kind = 'nonsense' WHERE id = 2")
    removed = remove_run(2, str(db))
    data = removed.to_json()["removed"]
    assert data["id"] == 2 and "kind" in data["reason"]


HOSTILE = {
    "a title-setting escape": "q\x1b]2;PWNED\x1b\\",
    "clear the screen": "\x1b[2J\x1b[H",
    "an OSC 52 clipboard write": "\x1b]52;c;SGVsbG8=\x07",
    "rich markup": "[/bold]",
    "a bidirectional override": "q\u202elearning",
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_text_from_the_history_reaches_the_terminal_as_data(
    name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = HOSTILE[name]
    db = tmp_path / "runs.db"
    with RunHistory(db) as history:
        run_id = history.start_run(RunSpec(
            RunKind.TRAIN, text, text, seeds=(0,), game_params={text: text},
            hyperparameters={"note": text}, versions=None,
        ))
        history.update(run_id, curves=[Curve(text, [1, 2], [0.5, 0.25])],
                       figures=[Figure(text, 1.0, text)], agent_path=text,
                       status=RunStatus.FINISHED)
    for argv in (("runs",), ("runs", "show", "1"), ("runs", "rm", "1")):
        code, out, err = run_cli(capsys, *argv, "--db", str(db))
        assert code == 0, err
        assert "\x1b" not in out + err and "\u202e" not in out + err and "\x07" not in out
        if name == "rich markup":
            assert "[/bold]" in out  # shown as it is, not read as markup


def test_adding_curves_to_a_run_whose_curves_do_not_read_names_it(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    record_three(db)
    edit(db, *IN_THE_RECORD["a curve blob as text"])
    with RunHistory(db) as history:
        with pytest.raises(DamagedRunError, match="^run 2 in .*its curves do not decode"):
            history.update(2, curves=[Curve("more", [1], [0.5])])
        history.update(3, curves=[Curve("more", [1], [0.5])])  # the others take theirs
        assert history.get_run(3).curve("more") is not None


def test_a_run_of_a_book_figures_fifty_thousand_seeds_reads_back(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    seeds = tuple(range(50_000))  # Figure 6.6 at full size: 50,000 runs of each arm
    with RunHistory(db) as history:
        run_id = history.start_run(RunSpec(RunKind.COMPARE, "cliffwalking", "sarsa",
                                           seeds=seeds))
    with RunHistory(db) as history:
        assert history.get_run(run_id).summary.seeds == seeds
        assert [r.id for r in history.list_runs()] == [run_id]
