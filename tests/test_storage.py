"""Saving and loading agents: full round trips, atomic writes, and clear refusals of bad files."""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import re
import signal
import stat
import struct
import subprocess
import sys
import time
import tracemalloc
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session import storage
from tui_gym.session.session import Session
from tui_gym.session.storage import FORMAT_NAME, FORMAT_VERSION, StorageError, read_agent

W = WrapperChoice.make


def _trained(choices: tuple[WrapperChoice, ...] = (), episodes: int = 400) -> Session:
    hp = QLearning.hyperparameters(learning_rate=0.01, episodes=5_000, epsilon_final=0.1)
    session = Session("blackjack", {"sab": True}, choices=choices, hp=hp, seed=9)
    session.trainer.run(episodes=episodes)
    return session


CASES = {
    "dense": (),
    "sparse": (W("FlattenObservation"), W("StepPenalty", penalty=0.02)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_save_and_load_round_trip(case: str, tmp_path: Path) -> None:
    original = _trained(CASES[case])
    assert original.agent.dense == (case == "dense")
    path = original.save(tmp_path / "agent.tgym")
    assert path == tmp_path / "agent.tgym" and path.is_file()

    loaded = Session.load(path)
    q, keys = original.agent.table()
    q2, keys2 = loaded.agent.table()
    assert np.array_equal(q2, q)
    assert keys2 == keys
    if keys is not None:
        assert all(isinstance(k, tuple) for k in keys2)  # hashable again after JSON
    assert np.array_equal(loaded.agent.update_counts(), original.agent.update_counts())
    assert loaded.hp == original.hp
    assert loaded.env_id == original.env_id == "Blackjack-v1"
    assert loaded.env_kwargs == original.env_kwargs == {"natural": False, "sab": True}
    assert loaded.choices == original.choices and loaded.applied == original.applied
    assert loaded.chain_repr() == original.chain_repr()
    assert loaded.seed == original.seed
    assert loaded.trainer.episodes == original.trainer.episodes == 400
    assert loaded.trainer.steps == original.trainer.steps
    assert loaded.agent.episode == original.agent.episode
    assert loaded.agent.epsilon == original.agent.epsilon


@pytest.mark.parametrize("case", list(CASES))
def test_the_loaded_agent_plays_like_the_original(case: str, tmp_path: Path) -> None:
    original = _trained(CASES[case])
    loaded = Session.load(original.save(tmp_path / "agent.tgym"))
    _, keys = original.agent.table()
    states = keys if keys is not None else range(original.keyer.n_states)
    assert [loaded.agent.greedy_actions(k) for k in states] == [
        original.agent.greedy_actions(k) for k in states
    ]
    assert loaded.reference() == original.reference()
    assert loaded.evaluate(300, seed=4) == original.evaluate(300, seed=4)


def test_training_resumes_where_it_stopped(tmp_path: Path) -> None:
    original = _trained()
    loaded = Session.load(original.save(tmp_path / "agent.tgym"))
    loaded.trainer.run(episodes=100)
    assert loaded.trainer.episodes == 500 and loaded.trainer.remaining == 4_500


def test_saving_over_a_file_replaces_it(tmp_path: Path) -> None:
    path = tmp_path / "agent.tgym"
    session = _trained(episodes=100)
    session.save(path)
    session.trainer.run(episodes=100)
    session.save(path)
    assert Session.load(path).trainer.episodes == 200
    assert [p.name for p in tmp_path.iterdir()] == ["agent.tgym"]


def test_save_is_atomic_when_the_rename_fails(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "agent.tgym"
    session = _trained(episodes=100)
    session.save(path)
    before = path.read_bytes()
    session.trainer.run(episodes=100)

    def broken_replace(src: str, dst: str) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(StorageError) as caught:
        session.save(path)
    assert str(path) in str(caught.value) and "No space left" in str(caught.value)
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["agent.tgym"]  # no temp file left
    assert Session.load(path).trainer.episodes == 100


def test_an_interrupted_save_leaves_no_temp_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "agent.tgym"

    def interrupted(src: str, dst: str) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        _trained(episodes=10).save(path)
    assert list(tmp_path.iterdir()) == []


def test_save_into_a_missing_folder_is_a_storage_error(tmp_path: Path) -> None:
    path = tmp_path / "no" / "such" / "agent.tgym"
    with pytest.raises(StorageError) as caught:
        _trained(episodes=10).save(path)
    assert str(path) in str(caught.value)


def test_saving_through_a_symlink_writes_the_file_it_points_to(tmp_path: Path) -> None:
    (tmp_path / "real").mkdir()
    target = tmp_path / "real" / "agent.tgym"
    link = tmp_path / "link.tgym"
    link.symlink_to(target)  # dangling at first: the first save creates the target
    session = _trained(episodes=100)
    assert session.save(link) == link
    assert link.is_symlink() and target.is_file()
    session.trainer.run(episodes=100)
    session.save(link)
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert Session.load(target).trainer.episodes == 200
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == ["agent.tgym"]


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_a_new_save_gets_its_mode_from_the_umask(tmp_path: Path, umask: int, mode: int) -> None:
    session = _trained(episodes=10)
    old = os.umask(umask)
    try:
        path = session.save(tmp_path / "agent.tgym")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == mode


def test_a_replaced_save_keeps_its_mode(tmp_path: Path) -> None:
    session = _trained(episodes=10)
    path = session.save(tmp_path / "agent.tgym")
    path.chmod(0o640)
    session.save(path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o640


def test_stale_temp_files_of_a_killed_writer_are_removed(tmp_path: Path) -> None:
    path = tmp_path / "agent.tgym"
    dead = tmp_path / ".agent.tgym.999999999.0a1b2c3d.tmp"  # beyond any pid: its writer is gone
    old_style = tmp_path / ".agent.tgym.k3j_x9ab.tmp"  # from tempfile, an hour old
    live = tmp_path / f".agent.tgym.{os.getpid()}.0a1b2c3d.tmp"  # a writer still running
    fresh = tmp_path / ".agent.tgym.zzzzzzzz.tmp"  # just made: may be mid-write
    other = tmp_path / ".other.tgym.999999999.0a1b2c3d.tmp"  # another file's
    for file in (dead, old_style, live, fresh, other):
        file.write_bytes(b"partial")
    an_hour_ago = time.time() - 3600
    os.utime(old_style, (an_hour_ago, an_hour_ago))
    _trained(episodes=10).save(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        p.name for p in (path, live, fresh, other)
    )


def test_a_kill_during_a_write_leaves_a_temp_file_the_next_save_removes(tmp_path: Path) -> None:
    path = tmp_path / "agent.tgym"
    _trained(episodes=10).save(path)
    before = path.read_bytes()
    # A child saves over the file and is killed (SIGKILL: no cleanup can run) between
    # writing its temporary file and renaming it into place.
    script = (
        "import os, signal, sys\n"
        "from tui_gym.session.session import Session\n"
        "os.replace = lambda *a: os.kill(os.getpid(), signal.SIGKILL)\n"
        "Session('blackjack').save(sys.argv[1])\n"
    )
    child = subprocess.run([sys.executable, "-c", script, str(path)], timeout=120)
    assert child.returncode == -signal.SIGKILL
    leftovers = [p.name for p in tmp_path.iterdir() if p != path]
    assert len(leftovers) == 1 and leftovers[0].startswith(".agent.tgym.")
    assert path.read_bytes() == before  # the old file is whole
    _trained(episodes=10).save(path)
    assert [p.name for p in tmp_path.iterdir()] == ["agent.tgym"]


@pytest.fixture(params=["none", "SIG_IGN", "a function"])
def sigint_left_behind(request: pytest.FixtureRequest) -> Iterator[None]:
    """A SIGINT handler an earlier test in this process may leave (a child's SIG_IGN, an
    app's own), put back as it was afterwards."""
    found = signal.getsignal(signal.SIGINT)
    left = {"none": found, "SIG_IGN": signal.SIG_IGN, "a function": lambda *args: None}
    signal.signal(signal.SIGINT, left[request.param])
    yield
    signal.signal(signal.SIGINT, found)


@contextlib.contextmanager
def python_sigint() -> Iterator[None]:
    """SIGINT as Python starts a program (KeyboardInterrupt), then the handler found."""
    found = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, found)


@pytest.mark.usefixtures("sigint_left_behind")
def test_a_signal_during_a_write_waits_for_the_write(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "agent.tgym"
    real_fsync = os.fsync

    def fsync_then_interrupt(fd: int) -> None:
        real_fsync(fd)
        signal.raise_signal(signal.SIGINT)  # ctrl+c in the middle of the write

    with python_sigint():
        monkeypatch.setattr(os, "fsync", fsync_then_interrupt)
        with pytest.raises(KeyboardInterrupt):
            _trained(episodes=10).save(path)
        monkeypatch.undo()
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert [p.name for p in tmp_path.iterdir()] == ["agent.tgym"]
    assert Session.load(path).trainer.episodes == 10


@pytest.mark.parametrize(
    ("name", "fragment"),
    [
        ("", "the path is empty"),
        ("  ", "the path is empty"),
        ("no/such/agent.tgym", "the folder"),
        (".", "is a folder"),
        ("sub/", "a file name is needed"),
        ("file/agent.tgym", "is not a folder"),
    ],
)
def test_check_save_path_refuses_what_cannot_be_written(
    name: str, fragment: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    (tmp_path / "file").write_text("x")
    with pytest.raises(StorageError, match=re.escape(fragment)):
        storage.check_save_path(name)
    assert storage.check_save_path("agent.tgym") == Path("agent.tgym")


def test_saving_over_a_device_is_refused(tmp_path: Path) -> None:
    with pytest.raises(StorageError, match="not a regular file"):
        _trained(episodes=10).save("/dev/null")


# -- files that are not saves ---------------------------------------------------


def _zip(entries: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries.items():
            zf.writestr(name, data)
    return buf.getvalue()


@pytest.fixture(scope="module")
def saves(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    """The bytes of a good dense (Blackjack) and sparse (FlattenObservation) save."""
    folder = tmp_path_factory.mktemp("saves")
    return {
        "dense": _trained(episodes=50).save(folder / "dense.tgym").read_bytes(),
        "sparse": _trained(CASES["sparse"], episodes=50).save(folder / "sparse.tgym").read_bytes(),
    }


def _entries(raw: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        return {name: zf.read(name) for name in zf.namelist()}


def _with_entries(raw: bytes, **entries: bytes) -> bytes:
    return _zip({**_entries(raw), **{k.replace("_", "."): v for k, v in entries.items()}})


def _with_meta(raw: bytes, **changes: object) -> bytes:
    meta = json.loads(_entries(raw)["meta.json"])
    meta.update(changes)
    return _with_entries(raw, meta_json=json.dumps(meta).encode())  # ±Infinity as JSON writes it


def _with_meta_text(raw: bytes, field: str, text: str) -> bytes:
    """The meta with one field's value replaced by raw JSON text (for nesting no encoder makes)."""
    meta = json.loads(_entries(raw)["meta.json"])
    meta[field] = "@@"
    return _with_entries(raw, meta_json=json.dumps(meta).replace('"@@"', text).encode())


def _keys(raw: bytes) -> list:
    return json.loads(_entries(raw)["keys.json"])


def _npy(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()


def _npy_declaring(shape: tuple[int, ...], size: int = 128) -> bytes:
    """A small .npy whose header declares `shape` (float64) over a few bytes of data."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buf, {"descr": "<f8", "fortran_order": False, "shape": shape}
    )
    return buf.getvalue().ljust(size, b"\0")


def _with_table(raw: bytes, change) -> bytes:
    q = np.load(io.BytesIO(_entries(raw)["q.npy"]))
    return _with_entries(raw, q_npy=_npy(change(q.copy())))


def _flipped_table_byte(raw: bytes) -> bytes:
    """One byte of q.npy's compressed data flipped, in place in the archive."""
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        info = zf.getinfo("q.npy")
    data = bytearray(raw)
    header = info.header_offset
    name_len, extra_len = struct.unpack("<HH", data[header + 26 : header + 30])
    start = header + 30 + name_len + extra_len
    data[start + info.compress_size // 2] ^= 0xFF
    return bytes(data)


def _zip_bomb(declared: int) -> bytes:
    """An archive whose q.npy unpacks to `declared` zero bytes (a few kB on disk)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("meta.json", json.dumps({"format": FORMAT_NAME, "version": 1}))
        with zf.open("q.npy", "w", force_zip64=True) as fh:
            chunk = bytes(1 << 20)
            for _ in range(declared >> 20):
                fh.write(chunk)
    return buf.getvalue()


def _npz() -> bytes:
    buf = io.BytesIO()
    np.savez(buf, q=np.zeros((3, 2)))
    return buf.getvalue()


NOT_SAVES = {
    "random bytes": (lambda good: bytes(range(256)) * 8, "corrupt or truncated"),
    "empty": (lambda good: b"", "corrupt or truncated"),
    "truncated": (lambda good: good[: len(good) // 2], "corrupt or truncated"),
    "plain zip": (lambda good: _zip({"readme.txt": b"hello"}), "no meta.json"),
    "json file": (lambda good: json.dumps({"format": FORMAT_NAME}).encode(), "not a tui-gym"),
    "numpy npz": (lambda good: _npz(), "no meta.json"),
    "other format": (lambda good: _with_meta(good, format="something-else"), "format"),
    "newer version": (lambda good: _with_meta(good, version=FORMAT_VERSION + 1), "newer tui-gym"),
    "no version": (lambda good: _with_meta(good, version="one"), "no valid format version"),
    "flipped byte in the table": (_flipped_table_byte, "corrupt or truncated"),
}

# Each crafted file: how it is made from a good save, and the field the refusal must name.
CRAFTED: dict[str, tuple[str, object, str]] = {
    "meta not json": ("dense", lambda good: _with_entries(good, meta_json=b"{oops"),
                      "meta.json is not JSON"),
    "meta not utf-8": ("dense", lambda good: _with_entries(good, meta_json=b'{"a": "\xff"}'),
                       "meta.json is not UTF-8"),
    "no table": ("dense", lambda good: _zip({"meta.json": _entries(good)["meta.json"]}),
                 "q.npy is missing"),
    "version 0": ("dense", lambda good: _with_meta(good, version=0), "version must be positive"),
    "version -3": ("dense", lambda good: _with_meta(good, version=-3), "version must be positive"),
    "seed 1.5": ("dense", lambda good: _with_meta(good, seed=1.5), "seed must be an integer"),
    "seed text": ("dense", lambda good: _with_meta(good, seed="7"), "seed must be an integer"),
    "seed negative": ("dense", lambda good: _with_meta(good, seed=-1), "seed must be an integer"),
    "seed huge": ("dense", lambda good: _with_meta(good, seed=10**30), "seed must be an integer"),
    **{
        f"{field} {sign}Infinity": (
            "dense", lambda good, f=field, v=value: _with_meta(good, **{f: v}),
            f"{field} must be an integer",
        )
        for field in ("seed", "agent_episode", "episodes_trained", "steps_trained")
        for sign, value in (("+", math.inf), ("-", -math.inf))
    },
    "negative episodes": ("dense", lambda good: _with_meta(good, episodes_trained=-5),
                          "episodes_trained must be an integer"),
    "steps as bool": ("dense", lambda good: _with_meta(good, steps_trained=True),
                      "steps_trained must be an integer"),
    "wrappers [1]": ("dense", lambda good: _with_meta(good, wrappers=[1]),
                     "wrappers[0] must be a spec"),
    "wrappers [null]": ("dense", lambda good: _with_meta(good, wrappers=[None]),
                        "wrappers[0] must be a spec"),
    'wrappers [["TimeLimit"]]': ("dense", lambda good: _with_meta(good, wrappers=[["TimeLimit"]]),
                                 "wrappers[0] must be a spec"),
    "wrappers not a list": ("dense", lambda good: _with_meta(good, wrappers="TimeLimit"),
                            "wrappers must be a list"),
    "wrapper out of range": (
        "dense", lambda good: _with_meta(good, wrappers=["TimeLimit:max_episode_steps=0"]),
        "wrappers[0] is not valid: TimeLimit.max_episode_steps is out of range",
    ),
    "wrapper that does not fit": (
        "dense", lambda good: _with_meta(good, wrappers=["DistanceShaping"]),
        "wrappers[0] does not fit Blackjack-v1",
    ),
    "unknown wrapper": ("dense", lambda good: _with_meta(good, wrappers=["Nope"]),
                        "wrappers[0] is not valid: unknown wrapper 'Nope'"),
    "keys.json is 5": ("dense", lambda good: _with_entries(good, keys_json=b"5"),
                       "keys.json must be a list"),
    "keys.json on a dense table": (
        "dense", lambda good: _with_entries(good, keys_json=json.dumps(list(range(704))).encode()),
        "keys.json is for a sparse table; Blackjack-v1's is dense",
    ),
    "a row short": (
        "dense",
        lambda good: _with_entries(_with_table(good, lambda q: q[:-1]),
                                   counts_npy=_npy(np.zeros((703, 2), np.int64)),
                                   visits_npy=_npy(np.zeros(703, np.int64))),
        "q.npy has 703 rows; Blackjack-v1 has 704",
    ),
    "sparse table without keys": (
        "sparse", lambda good: _zip({k: v for k, v in _entries(good).items() if k != "keys.json"}),
        "keys.json is missing",
    ),
    "keys miscounted": (
        "sparse", lambda good: _with_entries(good, keys_json=b"[[1, 2]]"), "keys.json has 1 keys",
    ),
    "keys repeated": (
        "sparse",
        lambda good: _with_entries(good, keys_json=json.dumps(
            [_keys(good)[0]] * len(_keys(good))
        ).encode()),
        "keys.json names a state twice",
    ),
    "key nested": (
        "sparse",
        lambda good: _with_entries(good, keys_json=json.dumps([[[1]]] + _keys(good)[1:]).encode()),
        "keys.json[0] is not a state key",
    ),
    "deep nesting in meta": (
        "dense", lambda good: _with_meta_text(good, "hyperparameters", "[" * 10**5 + "]" * 10**5),
        "meta.json nests deeper than",
    ),
    "nesting in env_kwargs": (
        "dense", lambda good: _with_meta_text(good, "env_kwargs", '{"a":' * 50 + "1" + "}" * 50),
        "meta.json nests deeper than",
    ),
    "deep nesting in keys": (
        "sparse", lambda good: _with_entries(good, keys_json=b"[" * 50_000 + b"]" * 50_000),
        "keys.json nests deeper than",
    ),
    "huge integer in meta": (
        "dense", lambda good: _with_meta_text(good, "seed", "9" * 5000),
        "meta.json holds a number too long",
    ),
    "q.npy declaring 10^12 rows": (
        "dense", lambda good: _with_entries(good, q_npy=_npy_declaring((10**12, 2))),
        "q.npy declares 1,000,000,000,000 x 2 entries",
    ),
    "q.npy declaring more than it holds": (
        "dense", lambda good: _with_entries(good, q_npy=_npy_declaring((704, 2))),
        "q.npy declares 704 x 2 entries but holds",
    ),
    "q.npy not numpy": ("dense", lambda good: _with_entries(good, q_npy=b"hello"),
                        "q.npy is not a numpy array file"),
    "q.npy of objects": ("dense", lambda good: _with_entries(good, q_npy=_npy_declaring_objects()),
                         "q.npy holds object values"),
    "q.npy of integers": (
        "dense", lambda good: _with_entries(good, q_npy=_npy(np.zeros((704, 2), dtype=np.int64))),
        "q.npy holds int64 values",
    ),
    "q.npy 3-D": ("dense", lambda good: _with_entries(good, q_npy=_npy(np.zeros((704, 2, 1)))),
                  "q.npy must be a 2-D table"),
    "NaN Q-value": ("dense", lambda good: _with_table(good, lambda q: _put(q, math.nan)),
                    "q.npy holds NaN or infinite Q-values"),
    "infinite Q-value": ("dense", lambda good: _with_table(good, lambda q: _put(q, -math.inf)),
                         "q.npy holds NaN or infinite Q-values"),
    "negative counts": (
        "dense", lambda good: _with_entries(good, counts_npy=_npy(-np.ones((704, 2), np.int64))),
        "counts.npy holds negative",
    ),
    "counts of another shape": (
        "dense", lambda good: _with_entries(good, counts_npy=_npy(np.ones((3, 2), np.int64))),
        "counts.npy has shape (3, 2)",
    ),
    "hyperparameters out of range": (
        "dense", lambda good: _with_meta(good, hyperparameters={"learning_rate": 7}),
        "hyperparameters is not valid: learning_rate is out of range",
    ),
    "hyperparameters a list": ("dense", lambda good: _with_meta(good, hyperparameters=[1]),
                               "hyperparameters must be an object"),
    "env_kwargs a list": ("dense", lambda good: _with_meta(good, env_kwargs=[1]),
                          "env_kwargs must be an object"),
    "env_kwargs unknown": ("dense", lambda good: _with_meta(good, env_kwargs={"size": 4}),
                           "env_kwargs is not valid"),
    "n_actions wrong": ("dense", lambda good: _with_meta(good, n_actions=3), "n_actions is 3"),
    "wrong game": (
        "dense", lambda good: _with_meta(good, env_id="tui_gym/GridWorld-v0", env_kwargs={}),
        "n_actions is 2; tui_gym/GridWorld-v0 with these wrappers has 4",
    ),
    "game arguments of another game": (
        "dense", lambda good: _with_meta(good, env_id="tui_gym/GridWorld-v0"),
        "env_kwargs is not valid: GridWorld takes size",
    ),
    "unknown game": ("dense", lambda good: _with_meta(good, env_id="Pong-v9"),
                     "env_id is not valid: unknown environment 'Pong-v9'"),
    "game id a number": ("dense", lambda good: _with_meta(good, env_id=5),
                         "env_id must be a game id"),
}


def _put(q: np.ndarray, value: float) -> np.ndarray:
    q[3, 1] = value
    return q


def _npy_declaring_objects() -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "|O", "fortran_order": False,
                                               "shape": (704, 2)})
    return buf.getvalue() + b"\0" * 64


def _refused(path: Path) -> str:
    with pytest.raises(StorageError) as caught:
        Session.load(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ")
    assert "\n" not in message and len(message) < 400 + len(str(path))
    return message


@pytest.mark.parametrize("case", list(NOT_SAVES))
def test_files_that_are_not_saves_are_refused_naming_the_file(
    case: str, tmp_path: Path, saves: dict[str, bytes]
) -> None:
    make, fragment = NOT_SAVES[case]
    path = tmp_path / f"{case.replace(' ', '-')}.tgym"
    path.write_bytes(make(saves["dense"]))
    assert fragment in _refused(path)


@pytest.mark.parametrize("case", list(CRAFTED))
def test_crafted_files_are_refused_naming_the_file_and_the_field(
    case: str, tmp_path: Path, saves: dict[str, bytes]
) -> None:
    kind, make, fragment = CRAFTED[case]
    path = tmp_path / "crafted.tgym"
    path.write_bytes(make(saves[kind]))  # type: ignore[operator]
    message = _refused(path)
    assert fragment in message, message


def test_a_zip_bomb_is_refused_before_it_is_unpacked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The same check at a smaller cap, so the bomb is quick to build.
    monkeypatch.setattr(storage, "MAX_TABLE_BYTES", 1 << 20)
    path = tmp_path / "bomb.tgym"
    path.write_bytes(_zip_bomb(8 << 20))
    assert path.stat().st_size < 40_000
    assert "q.npy would unpack to 8,388,608 bytes (at most 1,048,576)" in _refused(path)


def test_a_full_size_zip_bomb_is_refused_in_little_memory(tmp_path: Path) -> None:
    path = tmp_path / "bomb.tgym"
    path.write_bytes(_zip_bomb(storage.MAX_TABLE_BYTES + (1 << 20)))  # 129 MiB, 130 kB on disk
    tracemalloc.start()
    try:
        message = _refused(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert "q.npy would unpack to 135,266,304 bytes (at most 134,217,728)" in message
    assert peak < 4 << 20


def test_a_member_whose_size_lies_is_never_unpacked_past_it(tmp_path: Path) -> None:
    raw = bytearray(_zip({"meta.json": _bare_meta(), "q.npy": bytes(2 << 20)}))
    # Say 1,000 bytes in the local header and the directory instead of 2 MiB.
    two_mib = struct.pack("<I", 2 << 20)
    assert raw.count(two_mib) == 2
    path = tmp_path / "liar.tgym"
    path.write_bytes(bytes(raw.replace(two_mib, struct.pack("<I", 1000))))
    assert "corrupt or truncated" in _refused(path)  # the checksum of the first 1,000 bytes


def _bare_meta() -> bytes:
    return json.dumps(
        {"format": FORMAT_NAME, "version": FORMAT_VERSION, "algorithm": "q-learning"}
    ).encode()


def test_a_file_too_large_to_be_a_save_is_not_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(storage, "MAX_FILE_BYTES", 1000)
    path = tmp_path / "big.tgym"
    path.write_bytes(bytes(1001))
    assert "1,001 bytes; saves are at most 1,000" in _refused(path)


def test_pipes_and_devices_are_refused_without_reading(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo.tgym"
    os.mkfifo(fifo)
    assert "is a named pipe, not a save file" in _refused(fifo)  # and returns: no writer needed
    assert "is a device, not a save file" in _refused(Path("/dev/zero"))


def test_unreadable_files_say_so(tmp_path: Path) -> None:
    if os.geteuid() == 0:
        pytest.skip("root reads every file")
    path = tmp_path / "locked.tgym"
    path.write_bytes(b"x")
    path.chmod(0)
    assert "cannot read (Permission denied)" in _refused(path)


def test_newer_version_says_to_upgrade(tmp_path: Path, saves: dict[str, bytes]) -> None:
    path = tmp_path / "future.tgym"
    path.write_bytes(_with_meta(saves["dense"], version=FORMAT_VERSION + 1))
    with pytest.raises(StorageError, match="upgrade tui-gym"):
        read_agent(path)


def test_missing_file_and_folder(tmp_path: Path) -> None:
    with pytest.raises(StorageError) as caught:
        Session.load(tmp_path / "nothing.tgym")
    assert str(caught.value) == f"{tmp_path / 'nothing.tgym'}: no such file"
    with pytest.raises(StorageError) as caught:
        Session.load(tmp_path)
    assert str(tmp_path) in str(caught.value) and "folder" in str(caught.value)


def test_a_save_without_counts_still_loads(tmp_path: Path) -> None:
    # Version 1 files written before update counts were saved have no counts.npy.
    original = _trained(episodes=50)
    raw = original.save(tmp_path / "a.tgym").read_bytes()
    entries = _entries(raw)
    meta = json.loads(entries["meta.json"])
    meta["version"] = 1
    del meta["algorithm"], meta["learner"]
    old = tmp_path / "old.tgym"
    old.write_bytes(_zip({"meta.json": json.dumps(meta).encode(), "q.npy": entries["q.npy"]}))
    loaded = Session.load(old)
    assert loaded.algorithm == "q-learning"
    assert np.array_equal(loaded.agent.table()[0], original.agent.table()[0])
