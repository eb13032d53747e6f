"""Saving and loading agents: one versioned file, written atomically, read trusting nothing
(sizes capped, headers and fields checked, env ids resolved as data); a refusal is one
`StorageError` line."""

from __future__ import annotations

import io
import json
import math
import struct
import zipfile
import zlib
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from tui_gym.algorithms import Learner, LearnerState, QLearning, Settings, algorithm
from tui_gym.core.files import (
    OutputPathError,
    check_output_path,
    read_regular_file,
    write_atomically,
)
from tui_gym.core.params import shown_value
from tui_gym.core.text import nested_deeper
from tui_gym.core.wrappers.catalog import WrapperChoice

FORMAT_NAME = "tui-gym-agent"
FORMAT_VERSION = 2

MAX_FILE_BYTES = 256 << 20  # the archive on disk
MAX_META_BYTES = 1 << 20  # meta.json unpacked
MAX_TABLE_BYTES = 128 << 20  # each array's .npy and keys.json, unpacked
MAX_ROWS = 4_000_000  # table rows (the largest dense table has 2,000,000)
MAX_JSON_DEPTH = 8
MAX_COUNT = 2**62  # episodes, steps and update counts
MAX_SEED = 2**63 - 1


class StorageError(ValueError):
    """A save file that cannot be written or read; the message names the file."""


# -- writing --------------------------------------------------------------------------------


def check_save_path(path: str | Path) -> Path:
    """`path` as a `Path` when a save can be written there; else `StorageError` saying why."""
    try:
        return check_output_path(path)
    except OutputPathError as error:
        raise StorageError(str(error)) from None


def save_agent(path: str | Path, meta: dict[str, Any], state: LearnerState) -> Path:
    """Save a learner's state and the session's `meta` (JSON data) to `path` atomically."""
    path = check_save_path(path)
    meta = {"format": FORMAT_NAME, "version": FORMAT_VERSION, **meta, "learner": state.meta}
    members = {"meta.json": json.dumps(meta, indent=2).encode()}
    for name, array in state.arrays.items():
        buf = io.BytesIO()
        np.save(buf, array, allow_pickle=False)
        members[f"{name}.npy"] = buf.getvalue()
    if state.keys is not None:
        keys = [list(k) if isinstance(k, tuple) else k for k in state.keys]
        members["keys.json"] = json.dumps(keys).encode()
    rows = int(state.meta["rows"])
    for name, data in members.items():
        cap = MAX_META_BYTES if name == "meta.json" else MAX_TABLE_BYTES
        if len(data) > cap or rows > MAX_ROWS:
            # Never write a file this version would refuse to read.
            raise StorageError(f"{path}: cannot save: the table is too large ({rows:,} rows)")
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    try:
        write_atomically(path, buf.getvalue())
    except OutputPathError as error:
        raise StorageError(str(error)) from None
    except OSError as exc:
        raise StorageError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


# -- reading --------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Reader:
    """Messages for one file: every refusal names it."""

    path: Path

    def error(self, text: str) -> StorageError:
        """A `StorageError` naming the file."""
        return StorageError(f"{self.path}: {text}")

    def field(self, name: str, problem: str) -> StorageError:
        """A `StorageError` naming the file and the field at fault."""
        return StorageError(f"{self.path}: not a valid save file: {name} {problem}")

    def typed(self, value: Any, name: str, kind: type | tuple[type, ...], what: str) -> Any:
        """`value` when it is a `kind`; else refused as not `what`."""
        if not isinstance(value, kind):
            raise self.field(name, f"must be {what}, got {shown_value(value)}")
        return value

    def checked(self, name: str, build: Callable[[], Any]) -> Any:
        """`build()`, with a ValueError or TypeError it raises refused under the field's name."""
        try:
            return build()
        except StorageError:
            raise
        except (ValueError, TypeError, KeyError) as exc:
            raise self.field(name, f"is not valid: {short_reason(exc)}") from None


def _too_big(size: int | None) -> str:
    if size is None:
        return f"not a tui-gym save file (over {MAX_FILE_BYTES:,} bytes)"
    return f"not a tui-gym save file ({size:,} bytes; saves are at most {MAX_FILE_BYTES:,})"


def _member(reader: _Reader, zf: zipfile.ZipFile, name: str, cap: int) -> bytes | None:
    """One archive member, unpacked to at most `cap` bytes; None when it is absent."""
    try:
        info = zf.getinfo(name)
    except KeyError:
        return None
    if info.file_size > cap:
        raise reader.field(name, f"would unpack to {info.file_size:,} bytes (at most {cap:,})")
    with zf.open(info) as fh:
        data = fh.read(cap + 1)  # the declared size can lie: never unpack more than the cap
    if len(data) > cap:
        raise reader.field(name, f"unpacks to over {cap:,} bytes")
    return data


def _json(reader: _Reader, name: str, data: bytes) -> Any:
    try:
        value = json.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise reader.field(name, "is not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise reader.field(name, f"is not JSON ({exc.msg} at line {exc.lineno})") from None
    except RecursionError:
        raise reader.field(name, f"nests deeper than {MAX_JSON_DEPTH} levels") from None
    except ValueError:  # an integer too long to read
        raise reader.field(name, "holds a number too long to read") from None
    if nested_deeper(value, MAX_JSON_DEPTH):
        raise reader.field(name, f"nests deeper than {MAX_JSON_DEPTH} levels")
    return value


def _array(reader: _Reader, name: str, data: bytes, kinds: str, ndim: int = 2) -> np.ndarray:
    """A `.npy` array of `ndim` dimensions whose header agrees with its bytes, of kind `kinds`."""
    buf = io.BytesIO(data)
    try:
        major, _minor = np.lib.format.read_magic(buf)
        if major == 1:
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(buf)
        elif major in (2, 3):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(buf)
        else:
            raise ValueError("unknown .npy version")
    except (ValueError, EOFError, SyntaxError, TypeError):
        raise reader.field(name, "is not a numpy array file") from None
    if dtype.hasobject or dtype.kind not in kinds or dtype.itemsize == 0:
        raise reader.field(name, f"holds {dtype} values")
    if len(shape) != ndim:
        what = "a 2-D table" if ndim == 2 else "a 1-D array"
        raise reader.field(name, f"must be {what}, has shape {shape}")
    rows, columns = shape if ndim == 2 else (*shape, 1)
    if rows > MAX_ROWS or columns > 1024:
        raise reader.field(name, f"declares {rows:,} x {columns:,} entries (too large)")
    needed = rows * columns * dtype.itemsize
    if len(data) - buf.tell() != needed:
        raise reader.field(name, f"declares {rows:,} x {columns:,} entries but holds "
                           f"{len(data) - buf.tell():,} bytes of data, not {needed:,}")
    array = np.frombuffer(data, dtype=dtype, count=rows * columns, offset=buf.tell())
    return array.reshape(shape, order="F" if fortran else "C")


def _key_from_json(reader: _Reader, index: int, value: Any) -> Hashable:
    """A saved sparse key: a number, a string, or a flat list of numbers (made a tuple)."""
    if isinstance(value, list):
        if all(_plain_number(v) for v in value):
            return tuple(value)
    elif _plain_number(value) or isinstance(value, str):
        return value
    raise reader.field(f"keys.json[{index}]", f"is not a state key (got {shown_value(value)})")


def _plain_number(value: Any) -> bool:
    return type(value) is int or (type(value) is float and math.isfinite(value))  # JSON's types


# The dtype kinds each kind of learner array may be saved as.
_KINDS = {"f": "f", "i": "iu", "u": "iu", "b": "b"}


def _learner_arrays(
    reader: _Reader, zf: zipfile.ZipFile, cls: type[Learner], version: int
) -> dict[str, np.ndarray]:
    """Every array `cls` saves, from its `NAME.npy`, all with one row count."""
    if version < 2:
        return _version_1_arrays(reader, zf)
    blank = cls(1, n_states=1).state().arrays  # the names, kinds and dimensions it saves
    tables = [spec.name for spec in cls.tables]
    names = tables + [name for name in blank if name not in tables]
    lowest = {spec.name: min(0, int(spec.fill)) for spec in cls.tables if spec.dtype is not bool}
    arrays: dict[str, np.ndarray] = {}
    for name in names:
        like, member = blank[name], f"{name}.npy"
        data = _member(reader, zf, member, MAX_TABLE_BYTES)
        if data is None:
            raise reader.field(member, f"is missing (the {cls.title} learner saves it)")
        array = _array(reader, member, data, _KINDS[like.dtype.kind], like.ndim)
        _check_numbers(reader, member, array, lowest.get(name, 0))
        first = arrays.get(tables[0])
        if name in tables and first is not None and array.shape != first.shape:
            raise reader.field(member, f"has shape {array.shape}, {tables[0]}.npy {first.shape}")
        arrays[name] = array
    return arrays


def _version_1_arrays(reader: _Reader, zf: zipfile.ZipFile) -> dict[str, np.ndarray]:
    """Q-learning's arrays from a version 1 save: q.npy, and counts.npy when present."""
    q_bytes = _member(reader, zf, "q.npy", MAX_TABLE_BYTES)
    if q_bytes is None:
        raise reader.field("q.npy", "is missing (the Q-table)")
    q = _array(reader, "q.npy", q_bytes, "f").astype(np.float64)
    _check_numbers(reader, "q.npy", q)
    counts_bytes = _member(reader, zf, "counts.npy", MAX_TABLE_BYTES)
    if counts_bytes is None:
        # Unknown history: every learned value is taken as well established.
        counts = np.where(q != 0, 1_000_000, 0).astype(np.int64)
    else:
        counts = _array(reader, "counts.npy", counts_bytes, "iu")
        if counts.shape != q.shape:
            raise reader.field("counts.npy", f"has shape {counts.shape}, q.npy {q.shape}")
        _check_numbers(reader, "counts.npy", counts)
        counts = counts.astype(np.int64)
    return {"q": q, "counts": counts, "visits": counts.sum(axis=1)}


def _check_numbers(reader: _Reader, member: str, array: np.ndarray, lowest: int = 0) -> None:
    """Values no learner saves: NaN or infinite numbers, counts below `lowest` (-1 marks
    "never" in some tables, e.g. Dyna-Q's model) or impossibly large."""
    if array.dtype.kind == "f":
        if not np.isfinite(array).all():
            what = "Q-values" if member == "q.npy" else "values"
            raise reader.field(member, f"holds NaN or infinite {what}")
    elif array.dtype.kind in "iu" and array.size and (array.min() < lowest
                                                      or array.max() > MAX_COUNT):
        raise reader.field(member, "holds negative or impossible counts")


def short_reason(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 80 else text[:77] + "..."


def _check_version(reader: _Reader, version: Any) -> int:
    if version is None or isinstance(version, bool) or not isinstance(version, int):
        raise reader.error(f"save file has no valid format version (got {shown_value(version)})")
    if version < 1:
        raise reader.field("version", f"must be positive, got {shown_value(version)}")
    if version > FORMAT_VERSION:
        raise reader.error(f"saved by a newer tui-gym (format {shown_value(version)}; this one "
                           f"reads up to {FORMAT_VERSION}); upgrade tui-gym to open it")
    return version


def _keys(reader: _Reader, value: Any, rows: int) -> list[Hashable]:
    reader.typed(value, "keys.json", list, "a list of state keys")
    if len(value) != rows:
        raise reader.field("keys.json", f"has {len(value):,} keys for {rows:,} table rows")
    keys = [_key_from_json(reader, i, k) for i, k in enumerate(value)]
    if len(set(keys)) != len(keys):
        raise reader.field("keys.json", "names a state twice")
    return keys


def _int_field(
    reader: _Reader, meta: dict[str, Any], name: str, default: int, low: int, high: int
) -> int:
    value = meta.get(name, default)
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise reader.field(name, f"must be an integer in [{low}, {high}], got {shown_value(value)}")
    return value


@dataclass(frozen=True)
class SavedAgent(_Reader):
    """What a save file holds, checked as far as it can be without the game it names."""

    env_id: str
    env_kwargs: dict[str, Any]
    choices: tuple[WrapperChoice, ...]
    algorithm: type[Learner]
    hp: Settings
    seed: int
    episodes: int
    steps: int
    agent_episode: int
    n_actions: int | None  # None: the file does not say
    arrays: dict[str, np.ndarray]  # the learner's, by name; the first table's gives the shape
    keys: list[Hashable] | None
    meta: dict[str, Any]  # meta.json as read

    def check_learner_meta(self) -> None:
        """The learner's own metadata (format 2), which must agree with the tables;
        checked once the tables are known to fit the game (their fault is named first)."""
        rows, meta, name = len(self.arrays[self.table_name]), self.meta, self.algorithm.name
        if "learner" not in meta and meta.get("version", 1) < 2:
            return
        learner = self.typed(meta.get("learner"), "learner", dict, "an object")
        if learner.get("algorithm") != name:
            raise self.field("learner.algorithm",
                             f"is {shown_value(learner.get('algorithm'))}, not {name}")
        if learner.get("rows") != rows or isinstance(learner.get("rows"), bool):
            raise self.field("learner.rows",
                             f"is {shown_value(learner.get('rows'))}; the tables have {rows:,}")

    @property
    def table_name(self) -> str:
        return self.algorithm.tables[0].name

    def state(self, n_actions: int, n_states: int | None) -> LearnerState:
        """The learner state to load into a learner of `n_actions` and `n_states`."""
        return LearnerState(
            self.algorithm.name,
            self.arrays,
            {"n_actions": n_actions, "n_states": n_states,
             "rows": len(self.arrays[self.table_name]),
             "episode": self.agent_episode, "hyperparameters": self.hp.to_dict()},
            self.keys,
        )


def read_agent(path: str | Path) -> SavedAgent:
    """A save file's contents, checked but for the game and the learner's own rules (the
    session's part); `StorageError` when it is not a valid one."""
    from tui_gym.core.wrappers import check_chain_length, parse_wrapper_spec
    from tui_gym.games import UnknownGameError, resolve_env_id

    reader = _Reader(Path(path))
    raw = read_regular_file(reader.path, MAX_FILE_BYTES, "a save file", reader.error, _too_big)
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            meta_bytes = _member(reader, zf, "meta.json", MAX_META_BYTES)
            if meta_bytes is None:
                raise reader.error("not a tui-gym save file (no meta.json inside)")
            meta = _json(reader, "meta.json", meta_bytes)
            if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
                raise reader.error(f"not a tui-gym save file (format is not {FORMAT_NAME})")
            version = _check_version(reader, meta.get("version"))
            name = reader.typed(meta.get("algorithm") if version >= 2 else QLearning.name,
                                "algorithm", str, "an algorithm's name")  # version 1's is fixed
            cls = reader.checked("algorithm", partial(algorithm, name))
            arrays = _learner_arrays(reader, zf, cls, version)
            rows = len(arrays[cls.tables[0].name])
            keys = None
            keys_bytes = _member(reader, zf, "keys.json", MAX_TABLE_BYTES)
            if keys_bytes is not None:
                keys = _keys(reader, _json(reader, "keys.json", keys_bytes), rows)
    except StorageError:
        raise
    except (zipfile.BadZipFile, zlib.error, EOFError, ValueError, struct.error):
        # ValueError: zipfile's own, on offsets a damaged directory points past the start.
        raise reader.error("not a tui-gym save file (corrupt or truncated)") from None
    except (NotImplementedError, RuntimeError, zipfile.LargeZipFile, OSError) as exc:
        # Unsupported compression, encryption, ZIP64 oddities: not a file we wrote.
        raise reader.error(f"not a tui-gym save file ({short_reason(exc)})") from None
    except MemoryError:
        raise reader.error("not a tui-gym save file (too large to read)") from None

    env_id = reader.typed(meta.get("env_id"), "env_id", str, "a game id")
    try:  # resolved as data: never by importing a module
        env_id = resolve_env_id(env_id, from_data=True)
    except UnknownGameError as error:
        raise reader.field("env_id", f"is not valid: {error}") from None
    env_kwargs = reader.typed(meta.get("env_kwargs", {}), "env_kwargs", dict, "an object")
    wrappers = reader.typed(meta.get("wrappers", []), "wrappers", list, "a list of specs")
    reader.checked("wrappers", partial(check_chain_length, len(wrappers)))
    choices = []
    for i, spec in enumerate(wrappers):
        reader.typed(spec, f"wrappers[{i}]", str, "a spec like 'TimeLimit:max_episode_steps=50'")
        choices.append(reader.checked(f"wrappers[{i}]", partial(parse_wrapper_spec, spec)))
    hp_data = reader.typed(meta.get("hyperparameters"), "hyperparameters", dict, "an object")
    hp = reader.checked("hyperparameters", lambda: cls.settings(hp_data))
    seed = _int_field(reader, meta, "seed", 0, 0, MAX_SEED)
    episodes = _int_field(reader, meta, "episodes_trained", 0, 0, MAX_COUNT)
    steps = _int_field(reader, meta, "steps_trained", 0, 0, MAX_COUNT)
    agent_episode = _int_field(reader, meta, "agent_episode", episodes, 0, MAX_COUNT)
    n_actions = (_int_field(reader, meta, "n_actions", 1, 1, 1 << 20) if "n_actions" in meta
                 else None)
    reader.typed(meta.get("observation_space", ""), "observation_space", str, "text")
    if len(arrays["visits"]) != rows:
        raise reader.field("visits.npy",
                           f"has {len(arrays['visits']):,} entries for {rows:,} table rows")
    return SavedAgent(
        path=Path(path), env_id=env_id, env_kwargs=dict(env_kwargs), choices=tuple(choices),
        algorithm=cls, hp=hp, seed=seed, episodes=episodes, steps=steps,
        agent_episode=agent_episode, n_actions=n_actions, arrays=arrays, keys=keys, meta=meta,
    )
