"""Fuzz: save files. Every mutation of a good save either loads as a sound session or is
refused with one line naming the file; seeded, so every run tries the same files."""

from __future__ import annotations

import contextlib
import io
import json
import math
import random
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tui_gym.algorithms import QLearning
from tui_gym.cli import main
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.session import Session
from tui_gym.session.storage import StorageError

from .test_fuzz_params import nasty_text, nasty_value

SEED = 13
CASES = 300
META_FIELDS = ["format", "version", "env_id", "env_kwargs", "wrappers", "hyperparameters", "seed",
               "episodes_trained", "steps_trained", "agent_episode", "n_actions",
               "observation_space"]


@pytest.fixture(scope="module")
def saves(tmp_path_factory: pytest.TempPathFactory) -> list[bytes]:
    folder = tmp_path_factory.mktemp("fuzz-saves")
    hp = QLearning.hyperparameters(learning_rate=0.05, episodes=1_000)
    made = [
        Session("blackjack", hp=hp, seed=1),
        Session("blackjack", choices=(WrapperChoice.make("FlattenObservation"),), hp=hp, seed=2),
        Session("gridworld", {"size": 3}, hp=hp, seed=3),
    ]
    for i, session in enumerate(made):
        session.trainer.run(episodes=60)
        session.save(folder / f"{i}.tgym")
    return [(folder / f"{i}.tgym").read_bytes() for i in range(len(made))]


def _entries(raw: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        return {name: zf.read(name) for name in zf.namelist()}


def _zip(entries: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries.items():
            zf.writestr(name, data)
    return buf.getvalue()


def _npy(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()


def _json_bytes(value: object) -> bytes:
    try:
        return json.dumps(value).encode("utf-8", "surrogatepass")
    except (ValueError, RecursionError):
        return b"null"


def _random_array(rng: random.Random, like: np.ndarray) -> np.ndarray:
    dtype = rng.choice([np.float64, np.float32, np.float16, np.int64, np.uint64, np.int8,
                        np.bool_, np.complex128])
    rows = rng.choice([0, 1, like.shape[0] - 1, like.shape[0], like.shape[0] + 1])
    shape = rng.choice([(rows, like.shape[1]), (rows, like.shape[1] + 1), (rows,),
                        (rows, like.shape[1], 1), like.shape])
    array = np.zeros(shape, dtype=dtype)
    if array.size:
        spots = np.unravel_index(
            [rng.randrange(array.size) for _ in range(3)], array.shape
        )
        special = rng.choice([math.nan, math.inf, -1, 2**62, -(2**40), 0.5, 1e300])
        with contextlib.suppress(OverflowError, ValueError, TypeError), np.errstate(all="ignore"):
            array[spots] = special  # inf in a float16, say: what a damaged file could hold
    return array


def mutate(rng: random.Random, raw: bytes) -> bytes:
    """One random damage to a save's bytes, members, fields or tables."""
    kind = rng.randrange(9)
    if kind == 0:  # bytes flipped anywhere in the archive
        data = bytearray(raw)
        for _ in range(rng.randint(1, 6)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        return bytes(data)
    if kind == 1:  # cut short, or padded with junk
        cut = rng.randrange(len(raw))
        junk = bytes(rng.randrange(256) for _ in range(cut % 64))
        return raw[:cut] if rng.random() < 0.5 else raw + junk
    entries = _entries(raw)
    if kind == 2:  # a member missing, replaced by junk, or added
        name = rng.choice([*entries, "extra.bin"])
        choice = rng.randrange(3)
        if choice == 0:
            entries.pop(name, None)
        else:
            entries[name] = bytes(rng.randrange(256) for _ in range(rng.randint(0, 200)))
        return _zip(entries)
    if kind in (3, 4, 5):  # a meta field set to a nasty value, or removed
        meta = json.loads(entries["meta.json"])
        field = rng.choice([*META_FIELDS, nasty_text(rng)])
        if rng.random() < 0.15:
            meta.pop(field, None)
        elif field == "hyperparameters" and rng.random() < 0.5 and isinstance(meta[field], dict):
            meta[field][rng.choice([*meta[field], "other"])] = nasty_value(rng)
        elif field == "wrappers" and rng.random() < 0.5:
            meta[field] = [rng.choice(["TimeLimit", "DistanceShaping", "StickyAction",
                                       "FlattenObservation", "TimeLimit:max_episode_steps=0"])
                           + rng.choice(["", ":x=1", f":delay={nasty_text(rng)}"])]
        else:
            meta[field] = nasty_value(rng)
        entries["meta.json"] = _json_bytes(meta)
        return _zip(entries)
    if kind == 6:  # the Q-table replaced
        q = np.load(io.BytesIO(entries["q.npy"]))
        entries["q.npy"] = _npy(_random_array(rng, q))
        return _zip(entries)
    if kind == 7:  # the counts replaced
        q = np.load(io.BytesIO(entries["q.npy"]))
        entries["counts.npy"] = _npy(_random_array(rng, q))
        return _zip(entries)
    # keys.json: nonsense, or the right keys with one spoiled
    keys = json.loads(entries.get("keys.json", b"[]"))
    if keys and rng.random() < 0.6:
        keys[rng.randrange(len(keys))] = nasty_value(rng)
        entries["keys.json"] = _json_bytes(keys)
    else:
        entries["keys.json"] = _json_bytes(nasty_value(rng))
    return _zip(entries)


def check_loaded(session: Session) -> None:
    """A session that loaded must be sound enough to use."""
    q, keys = session.agent.table()
    assert np.isfinite(q).all()
    assert (session.agent.update_counts() >= 0).all()
    assert session.trainer.episodes >= 0 and session.trainer.steps >= 0
    assert session.agent.episode >= 0 and 0 <= session.agent.epsilon <= 1
    assert not session.skipped
    session.reference()
    key = keys[0] if keys else 0
    session.agent.greedy_actions(key)


def test_every_damaged_save_loads_soundly_or_is_refused_in_one_line(
    saves: list[bytes], tmp_path: Path
) -> None:
    rng = random.Random(SEED)
    refused = 0
    for case in range(CASES):
        path = tmp_path / f"case-{case}.tgym"
        path.write_bytes(mutate(rng, rng.choice(saves)))
        try:
            session = Session.load(path)
        except StorageError as exc:
            message = str(exc)
            assert message.startswith(f"{path}: "), message
            assert "\n" not in message and len(message) < 300 + len(str(path)), message
            refused += 1
            continue
        check_loaded(session)
    assert refused > CASES // 2  # the mutations do damage


def test_eval_answers_damaged_saves_in_one_line(
    saves: list[bytes], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rng = random.Random(SEED + 1)
    for case in range(40):
        path = tmp_path / f"case-{case}.tgym"
        path.write_bytes(mutate(rng, rng.choice(saves)))
        code = main(["eval", str(path), "--episodes", "3", "--json"])
        out, err = capsys.readouterr()
        if code == 0:
            assert err == "" and json.loads(out)["episodes"] == 3
        else:
            assert code == 2 and out == ""
            assert err.count("\n") == 1 and err.startswith(f"tui-gym: error: {path}: ")


def hostile_env_id(rng: random.Random, module: str) -> str:
    """An env id a damaged or crafted save could name: module forms (the marker module,
    modules of the standard library), near misses, and nasty text."""
    bare = rng.choice(["Blackjack-v1", "FrozenLake-v1", "CliffWalking-v1", "Nope-v0", ""])
    return rng.choice([
        f"{module}:{bare}", f"{module}.sub:{bare}", f"this:{bare}", f"antigravity:{bare}",
        f"{nasty_text(rng)}:{bare}", f"::{bare}", f"{module}:", f" {module}:{bare} ",
        f"{bare}:{module}", nasty_text(rng), "x" * rng.choice([201, 5_000]), bare,
    ])


def test_saves_naming_hostile_env_ids_never_import_a_module(
    saves: list[bytes], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sys

    module = "tgym_fuzz_marker"
    marker = tmp_path / "marker"
    (tmp_path / f"{module}.py").write_text(f"open({str(marker)!r}, 'w').write('ran')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    before = set(sys.modules)
    rng = random.Random(SEED + 2)
    for case in range(60):
        entries = _entries(rng.choice(saves))
        meta = json.loads(entries["meta.json"])
        meta["env_id"] = hostile_env_id(rng, module)
        entries["meta.json"] = _json_bytes(meta)
        path = tmp_path / f"case-{case}.tgym"
        path.write_bytes(_zip(entries))
        try:
            Session.load(path)
        except StorageError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 400 + len(str(path)), str(exc)
    assert not marker.exists()
    assert {name.split(".")[0] for name in set(sys.modules) - before}.isdisjoint(
        {module, "this", "antigravity"})
