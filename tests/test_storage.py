"""Saving and loading agents: full round trips, atomic writes, and clear refusals of bad files."""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.core.agent import Hyperparameters
from tui_gym.core.session import Session
from tui_gym.core.storage import FORMAT_NAME, FORMAT_VERSION, StorageError, load_session
from tui_gym.core.wrappers import WrapperChoice

W = WrapperChoice.make


def _trained(choices: tuple[WrapperChoice, ...] = (), episodes: int = 400) -> Session:
    hp = Hyperparameters(learning_rate=0.01, episodes=5_000, epsilon_final=0.1)
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


# -- files that are not saves ---------------------------------------------------


def _zip(entries: dict[str, bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, data in entries.items():
            zf.writestr(name, data)
    return buf.getvalue()


def _good_save(tmp_path: Path) -> bytes:
    return _trained(episodes=50).save(tmp_path / "good.tgym").read_bytes()


def _with_meta(raw: bytes, **changes: object) -> bytes:
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        entries = {name: zf.read(name) for name in zf.namelist()}
    meta = json.loads(entries["meta.json"])
    meta.update(changes)
    entries["meta.json"] = json.dumps(meta).encode()
    return _zip(entries)


def _bare_meta() -> bytes:
    return json.dumps({"format": FORMAT_NAME, "version": FORMAT_VERSION}).encode()


def _npz() -> bytes:
    buf = io.BytesIO()
    np.savez(buf, q=np.zeros((3, 2)))
    return buf.getvalue()


BAD_FILES = {
    "random bytes": (lambda good: bytes(range(256)) * 8, "corrupt or truncated"),
    "empty": (lambda good: b"", "corrupt or truncated"),
    "truncated": (lambda good: good[: len(good) // 2], "corrupt or truncated"),
    "plain zip": (lambda good: _zip({"readme.txt": b"hello"}), "no meta.json"),
    "json file": (lambda good: json.dumps({"format": FORMAT_NAME}).encode(), "not a tui-gym"),
    "numpy npz": (lambda good: _npz(), "no meta.json"),
    "other format": (lambda good: _with_meta(good, format="something-else"), "format"),
    "newer version": (lambda good: _with_meta(good, version=FORMAT_VERSION + 1), "newer tui-gym"),
    "no version": (lambda good: _with_meta(good, version="one"), "version"),
    "meta not json": (lambda good: _zip({"meta.json": b"{oops"}), "corrupt save file"),
    "no table": (lambda good: _zip({"meta.json": _bare_meta()}), "corrupt save file"),
    "bad hyperparameters": (
        lambda good: _with_meta(good, hyperparameters={"learning_rate": 7}),
        "cannot restore",
    ),
    "wrong game": (lambda good: _with_meta(good, env_id="tui_gym/GridWorld-v0"), "cannot restore"),
    "unknown game": (lambda good: _with_meta(good, env_id="Pong-v9"), "cannot restore"),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_bad_files_raise_a_storage_error_naming_the_file(case: str, tmp_path: Path) -> None:
    make, fragment = BAD_FILES[case]
    path = tmp_path / f"{case.replace(' ', '-')}.tgym"
    path.write_bytes(make(_good_save(tmp_path)))
    with pytest.raises(StorageError) as caught:
        Session.load(path)
    message = str(caught.value)
    assert message.startswith(str(path))
    assert fragment in message
    assert "\n" not in message
    assert isinstance(caught.value, ValueError)


def test_newer_version_says_to_upgrade(tmp_path: Path) -> None:
    path = tmp_path / "future.tgym"
    path.write_bytes(_with_meta(_good_save(tmp_path), version=FORMAT_VERSION + 1))
    with pytest.raises(StorageError, match="upgrade tui-gym"):
        load_session(path)


def test_missing_file_and_folder(tmp_path: Path) -> None:
    with pytest.raises(StorageError) as caught:
        Session.load(tmp_path / "nothing.tgym")
    assert str(caught.value) == f"{tmp_path / 'nothing.tgym'}: no such file"
    with pytest.raises(StorageError) as caught:
        Session.load(tmp_path)
    assert str(tmp_path) in str(caught.value) and "folder" in str(caught.value)


def test_a_save_without_counts_still_loads(tmp_path: Path) -> None:
    # Files written before update counts were saved have no counts.npy.
    original = _trained(episodes=50)
    raw = original.save(tmp_path / "a.tgym").read_bytes()
    with zipfile.ZipFile(io.BytesIO(raw)) as zf:
        entries = {n: zf.read(n) for n in zf.namelist() if n != "counts.npy"}
    old = tmp_path / "old.tgym"
    old.write_bytes(_zip(entries))
    loaded = Session.load(old)
    assert np.array_equal(loaded.agent.table()[0], original.agent.table()[0])
