"""Saving and loading agents: one versioned file, written atomically.

The file is a zip archive (numpy's `.npz`) holding `meta.json` (format name
and version, env id and arguments, wrapper choices, hyperparameters, seed,
training counts) and `q.npy` (the Q-table); sparse tables add `keys.json`.
It is written to a temporary file in the same folder and renamed into place,
so a crash never leaves half a file. Anything that is not such a file (corrupt,
truncated, foreign, or from a newer version) raises `StorageError` naming it.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.agent import Hyperparameters

if TYPE_CHECKING:
    from tui_gym.core.session import Session

FORMAT_NAME = "tui-gym-agent"
FORMAT_VERSION = 1


class StorageError(ValueError):
    """A save file that cannot be written or read; the message names the file."""


def _key_to_json(key: Any) -> Any:
    return list(key) if isinstance(key, tuple) else key


def _key_from_json(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write `data` to `path` through a temporary file and a rename."""
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def session_meta(session: Session) -> dict[str, Any]:
    """Everything but the table, as JSON data."""
    from tui_gym.core.wrappers import format_wrapper_spec

    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "env_id": session.env_id,
        "env_kwargs": session.env_kwargs,
        "wrappers": [format_wrapper_spec(c) for c in session.choices],
        "hyperparameters": session.hp.to_dict(),
        "seed": session.seed,
        "episodes_trained": session.trainer.episodes,
        "steps_trained": session.trainer.steps,
        "agent_episode": session.agent.episode,
        "n_actions": session.agent.n_actions,
        "observation_space": session.keyer.signature,
    }


def save_session(session: Session, path: str | Path) -> Path:
    """Save a session's agent and settings to `path` (atomically)."""
    path = Path(path)
    q, keys = session.agent.table()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("meta.json", json.dumps(session_meta(session), indent=2))
        qbuf = io.BytesIO()
        np.save(qbuf, q, allow_pickle=False)
        zf.writestr("q.npy", qbuf.getvalue())
        cbuf = io.BytesIO()
        np.save(cbuf, session.agent.update_counts(), allow_pickle=False)
        zf.writestr("counts.npy", cbuf.getvalue())
        if keys is not None:
            zf.writestr("keys.json", json.dumps([_key_to_json(k) for k in keys]))
    try:
        atomic_write_bytes(path, buf.getvalue())
    except OSError as exc:
        raise StorageError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path


def read_file(
    path: str | Path,
) -> tuple[dict[str, Any], np.ndarray, list[Any] | None, np.ndarray | None]:
    """Meta, Q-table, sparse keys and update counts of a save file; StorageError if not one."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise StorageError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise StorageError(f"{path}: is a folder, not a save file") from None
    except OSError as exc:
        raise StorageError(f"{path}: cannot read ({exc.strerror or exc})") from None
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as zf:
            names = set(zf.namelist())
            if "meta.json" not in names:
                raise StorageError(f"{path}: not a tui-gym save file (no meta.json inside)")
            meta = json.loads(zf.read("meta.json").decode("utf-8"))
            if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
                raise StorageError(f"{path}: not a tui-gym save file (format is not {FORMAT_NAME})")
            version = meta.get("version")
            if not isinstance(version, int):
                raise StorageError(f"{path}: save file has no valid format version")
            if version > FORMAT_VERSION:
                raise StorageError(
                    f"{path}: saved by a newer tui-gym (format {version}; "
                    f"this one reads up to {FORMAT_VERSION}); upgrade tui-gym to open it"
                )
            q = np.load(io.BytesIO(zf.read("q.npy")), allow_pickle=False)
            counts = None
            if "counts.npy" in names:
                counts = np.load(io.BytesIO(zf.read("counts.npy")), allow_pickle=False)
            keys = None
            if "keys.json" in names:
                keys = [_key_from_json(k) for k in json.loads(zf.read("keys.json"))]
    except StorageError:
        raise
    except (zipfile.BadZipFile, EOFError):
        raise StorageError(f"{path}: not a tui-gym save file (corrupt or truncated)") from None
    except (KeyError, ValueError, UnicodeDecodeError, zipfile.LargeZipFile, OSError) as exc:
        raise StorageError(f"{path}: corrupt save file ({exc})") from None
    return meta, q, keys, counts


def load_session(path: str | Path) -> Session:
    """Rebuild a session (env, wrappers, hyperparameters, agent) from a save file."""
    from tui_gym.core.session import Session
    from tui_gym.core.wrappers import parse_wrapper_spec

    meta, q, keys, counts = read_file(path)
    try:
        session = Session(
            env_id=str(meta["env_id"]),
            env_kwargs=dict(meta.get("env_kwargs", {})),
            choices=tuple(parse_wrapper_spec(s) for s in meta.get("wrappers", [])),
            hp=Hyperparameters.from_dict(meta["hyperparameters"]),
            seed=int(meta.get("seed", 0)),
        )
        if q.ndim != 2 or q.shape[1] != session.agent.n_actions:
            raise ValueError(f"Q-table shape {q.shape} does not fit {session.env_id}")
        session.agent.load_table(q, keys, counts)
        session.agent.episode = int(meta.get("agent_episode", meta.get("episodes_trained", 0)))
        session.agent.set_hyperparameters(session.hp)
        session.trainer.episodes = int(meta.get("episodes_trained", 0))
        session.trainer.steps = int(meta.get("steps_trained", 0))
        session.trainer.publish()
    except StorageError:
        raise
    except (KeyError, TypeError, ValueError) as exc:
        raise StorageError(f"{path}: cannot restore the saved agent ({exc})") from None
    return session
