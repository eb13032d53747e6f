"""What the run history holds, as types: a run's settings, its curves, and what a query returns."""

from __future__ import annotations

import json
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from enum import StrEnum
from functools import cache
from importlib import metadata
from typing import Any

import numpy as np

from tui_gym.core.experiments.figures import FieldsJson, Figure


class RunKind(StrEnum):
    """What started a run."""

    TRAIN = "train"
    COMPARE = "compare"
    SWEEP = "sweep"
    APP = "app"
    BENCHMARK = "benchmark"


class RunStatus(StrEnum):
    """Where a run stands: running until it finishes, is interrupted (Ctrl+C, or its
    process ended without saying how) or fails."""

    RUNNING = "running"
    FINISHED = "finished"
    INTERRUPTED = "interrupted"
    FAILED = "failed"

    @classmethod
    def ending(cls, error: type[BaseException] | None) -> RunStatus:
        """How a run ends on `error`: finished without one, interrupted by Ctrl+C, else failed."""
        if error is None:
            return cls.FINISHED
        return cls.INTERRUPTED if issubclass(error, KeyboardInterrupt) else cls.FAILED


def _json_default(value: Any) -> Any:
    if isinstance(value, np.bool_ | np.integer | np.floating):
        return value.item()
    if isinstance(value, tuple | np.ndarray):
        return list(value)
    raise TypeError(f"{type(value).__name__} is not JSON data")


def to_json_text(value: Any, what: str) -> str:
    """Compact JSON text of `value`; ValueError naming `what` if it is not JSON data."""
    try:
        return json.dumps(value, separators=(",", ":"), allow_nan=False, default=_json_default)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what} cannot be recorded: {exc}") from None


def _timestamp(seconds: float | None) -> str | None:
    if seconds is None:
        return None
    return datetime.fromtimestamp(seconds, tz=UTC).isoformat(timespec="seconds")


@dataclass(frozen=True)
class WrapperSetting(FieldsJson):
    """One wrapper of a run: its catalog name and parameters."""

    name: str
    params: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Versions(FieldsJson):
    """The versions of the packages a run ran on ("" for one not installed)."""

    tui_gym: str
    gymnasium: str
    numpy: str
    python: str

    @classmethod
    @cache
    def current(cls) -> Versions:
        """The versions this process runs on."""
        from tui_gym import __version__

        try:
            gymnasium = metadata.version("gymnasium")
        except metadata.PackageNotFoundError:
            gymnasium = ""
        return cls(tui_gym=__version__, gymnasium=gymnasium, numpy=np.__version__,
                   python=platform.python_version())


@dataclass(frozen=True)
class RunSpec:
    """What a run is started with. `versions` None means the running interpreter's."""

    kind: RunKind
    game: str
    algorithm: str
    game_params: Mapping[str, Any] = field(default_factory=dict)
    wrappers: Sequence[WrapperSetting] = ()
    hyperparameters: Mapping[str, Any] = field(default_factory=dict)
    seeds: Sequence[int] = ()
    versions: Versions | None = None
    group: int | None = None  # the id of another run this one was launched with

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", RunKind(self.kind))
        object.__setattr__(self, "wrappers", tuple(self.wrappers))
        object.__setattr__(self, "seeds", tuple(int(s) for s in self.seeds))
        if not self.game:
            raise ValueError("a run needs a game")
        if not self.algorithm:
            raise ValueError("a run needs an algorithm")


@dataclass(frozen=True, eq=False)
class Curve:
    """One named curve: `values[i]` at episode `episodes[i]` (episodes strictly increasing)."""

    name: str
    episodes: np.ndarray
    values: np.ndarray

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("a curve needs a name")
        episodes = np.array(self.episodes, dtype=np.int64).ravel()
        values = np.array(self.values, dtype=np.float64).ravel()
        if len(episodes) != len(values):
            raise ValueError(
                f"curve {self.name!r}: {len(episodes)} episodes but {len(values)} values"
            )
        if len(episodes) > 1 and not np.all(np.diff(episodes) > 0):
            raise ValueError(f"curve {self.name!r}: episodes must be strictly increasing")
        if np.isinf(values).any():
            raise ValueError(f"curve {self.name!r}: values must be finite (or NaN for none)")
        episodes.setflags(write=False)
        values.setflags(write=False)
        object.__setattr__(self, "episodes", episodes)
        object.__setattr__(self, "values", values)

    @classmethod
    def per_episode(cls, name: str, values: np.ndarray, first_episode: int = 1) -> Curve:
        """A curve with one value per episode, numbered from `first_episode`."""
        values = np.asarray(values, dtype=np.float64).ravel()
        return cls(name, np.arange(first_episode, first_episode + len(values)), values)

    def __len__(self) -> int:
        return len(self.values)

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name, "episodes": self.episodes.tolist(),
            "values": [v if np.isfinite(v) else None for v in self.values.tolist()],
        }


@dataclass(frozen=True)
class RunSummary:
    """One run as a listing shows it."""

    id: int
    kind: RunKind
    game: str
    algorithm: str
    seeds: tuple[int, ...]
    status: RunStatus
    started_at: float  # seconds since the epoch
    ended_at: float | None
    figures: tuple[Figure, ...] = ()
    group: int | None = None

    @property
    def seconds(self) -> float | None:
        """How long the run took (None while it runs)."""
        return None if self.ended_at is None else self.ended_at - self.started_at

    def figure(self, name: str) -> Figure | None:
        return next((f for f in self.figures if f.name == name), None)

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id, "kind": str(self.kind), "game": self.game, "algorithm": self.algorithm,
            "seeds": list(self.seeds), "status": str(self.status),
            "started_at": _timestamp(self.started_at), "ended_at": _timestamp(self.ended_at),
            "seconds": self.seconds, "group": self.group,
            "figures": [f.to_json() for f in self.figures],
        }


@dataclass(frozen=True, eq=False)
class RunRecord:
    """Everything the history holds about one run."""

    summary: RunSummary
    game_params: Mapping[str, Any]
    wrappers: tuple[WrapperSetting, ...]
    hyperparameters: Mapping[str, Any]
    versions: Versions
    curves: tuple[Curve, ...]
    agent_path: str | None

    @property
    def id(self) -> int:
        return self.summary.id

    def curve(self, name: str) -> Curve | None:
        return next((c for c in self.curves if c.name == name), None)

    def to_json(self, *, curves: bool = True) -> dict[str, Any]:
        return {
            **self.summary.to_json(), "game_params": dict(self.game_params),
            "wrappers": [w.to_json() for w in self.wrappers],
            "hyperparameters": dict(self.hyperparameters), "versions": self.versions.to_json(),
            "agent_path": self.agent_path,
            "curves": [c.to_json() if curves else c.name for c in self.curves],
        }


@dataclass(frozen=True, eq=False)
class TaskRecord:
    """A finished task: seeds `seeds` (rows `rows` of the run's seed list), `episodes` each;
    `returns[i, e]`; `exact[i, j]` the greedy exact value (or RMS error of V) at checkpoint j."""

    rows: tuple[int, ...]
    seeds: tuple[int, ...]
    episodes: int
    returns: np.ndarray
    exact: np.ndarray | None = None
    algorithm: str = ""
    hyperparameters: Mapping[str, Any] = field(default_factory=dict)

    def inputs(self) -> dict[str, Any]:
        return {
            "rows": list(self.rows), "seeds": list(self.seeds), "episodes": self.episodes,
            "checkpoints": None if self.exact is None else int(self.exact.shape[1]),
            "algorithm": self.algorithm, "hyperparameters": dict(self.hyperparameters),
        }
