"""Sweeps: one algorithm over a grid of hyperparameter values, each point over many seeds."""

from __future__ import annotations

import itertools
import math
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tui_gym.algorithms import Predictor, algorithm
from tui_gym.core.experiments.figures import FieldsJson, plain
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.records import RunKind
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.experiments.compare import (
    AlgorithmOutcome,
    Arm,
    CompareProgress,
    Setup,
    execute,
    settle_runs,
)

__all__ = ["SWEEP_CURVE_POINTS", "Range", "SweepPoint", "SweepResult", "SweepSpec", "run_sweep"]

SWEEP_CURVE_POINTS = 100  # curve points per grid point in `to_json`
MAX_POINTS = 400  # grid points in one sweep at most


@dataclass(frozen=True)
class Range(FieldsJson):
    """Where a random search draws a key's values: `low` to `high`, log-uniform when `log`."""

    low: float
    high: float
    log: bool = False

    @classmethod
    def parse(cls, text: str) -> Range:
        """`LOW:HIGH` or `LOW:HIGH:log` (or `:lin`); ValueError saying what is wrong."""
        parts = text.split(":")
        scale = parts.pop() if len(parts) == 3 else "lin"
        try:
            low, high = (float(v) for v in parts) if len(parts) == 2 else (math.nan, math.nan)
        except ValueError:
            low = high = math.nan
        if not (math.isfinite(low) and math.isfinite(high)) or scale not in ("lin", "log"):
            raise ValueError(f"range {text!r}: expected LOW:HIGH or LOW:HIGH:log")
        if low >= high or (scale == "log" and low <= 0):
            raise ValueError(f"range {text!r}: LOW must be below HIGH"
                             + (" and above 0 for log" if scale == "log" else ""))
        return cls(low, high, scale == "log")

    def draw(self, rng: np.random.Generator) -> float:
        if self.log:
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        return float(rng.uniform(self.low, self.high))


@dataclass(frozen=True)
class SweepSpec:
    """`algorithm` on `game` at every point of `grid` (key -> values), or at `samples` points
    drawn from `ranges` by `sample_seed`, `seeds` seeds each; `settings` fix the others."""

    game: str
    algorithm: str
    grid: Mapping[str, Sequence[Any]]
    seeds: int
    episodes: int
    settings: Mapping[str, Any] = field(default_factory=dict)
    game_params: Mapping[str, Any] = field(default_factory=dict)
    wrappers: Sequence[WrapperChoice] = ()
    first_seed: int = 0
    ranges: Mapping[str, Range] = field(default_factory=dict)
    samples: int = 0
    sample_seed: int = 0

    def __post_init__(self) -> None:
        cls = algorithm(self.algorithm)
        object.__setattr__(self, "algorithm", cls.name)
        grid = {str(k): tuple(v) for k, v in self.grid.items()}
        ranges = {str(k): v for k, v in self.ranges.items()}
        if bool(ranges) != bool(self.samples):
            raise ValueError("a random search needs both --sample N and --range KEY=LOW:HIGH")
        if ranges and grid:
            raise ValueError("give --grid or --sample with --range, not both")
        if not grid and not ranges:
            raise ValueError("a sweep needs at least one --grid KEY=V1,V2 "
                             "(or --sample N --range KEY=LOW:HIGH)")
        fields = {f.name for f in cls.params}
        for key in [*ranges, *grid, *self.settings]:
            if key not in fields:
                raise ValueError(
                    f"{cls.name} has no hyperparameter {key!r}; it has {', '.join(sorted(fields))}"
                )
        for key, values in grid.items():
            if not values:
                raise ValueError(f"--grid {key}: give at least one value")
            if len(set(map(str, values))) != len(values):
                raise ValueError(f"--grid {key}: a value is listed twice")
        for key in self.settings:
            if key in grid or key in ranges:
                raise ValueError(f"{key} is both swept and set")
        count = self.samples if ranges else math.prod(len(v) for v in grid.values())
        if not 1 <= count <= MAX_POINTS:
            raise ValueError(f"the sweep has {count} points; from 1 to {MAX_POINTS} at once")
        settle_runs(self)
        object.__setattr__(self, "grid", grid)
        object.__setattr__(self, "ranges", ranges)

    @property
    def keys(self) -> list[str]:
        """The keys swept."""
        return list(self.ranges or self.grid)

    def points(self) -> list[dict[str, Any]]:
        """Every grid point as {key: value} (the first key slowest), or the points drawn."""
        if self.ranges:
            rng = np.random.default_rng(self.sample_seed)
            return [{k: r.draw(rng) for k, r in self.ranges.items()} for _ in range(self.samples)]
        keys = list(self.grid)
        return [dict(zip(keys, combo, strict=True))
                for combo in itertools.product(*self.grid.values())]


@dataclass(frozen=True)
class SweepPoint:
    """One grid point: its values (as the hyperparameters read them) and its outcome."""

    values: Mapping[str, Any]
    outcome: AlgorithmOutcome | None
    rank: int | None = None  # 1 for the best point's figure; None without one

    @property
    def figure(self) -> float | None:
        """What points rank by: a prediction learner's RMS error of V (the lower the better), else
        the greedy policy's exact value, else the online return over the last 10% of episodes."""
        o = self.outcome
        if o is None or (o.rms_error is None and issubclass(algorithm(o.algorithm), Predictor)):
            return None
        value = (o.rms_error if o.rms_error is not None else o.exact_value
                 if o.exact_value is not None else o.mean_return_last.mean)
        return value if math.isfinite(value) else None

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"values": dict(self.values), "rank": self.rank}
        o = self.outcome
        if o is None:
            data.update(seeds_done=0, episodes_done=0, mean_return_last=None, ci95=None,
                        exact_value=None, exact_gap=None, rms_error=None, rms_ci95=None,
                        rms_curve=None, run_id=None, curve=[])
            return data
        found = o.to_json(SWEEP_CURVE_POINTS)
        data.update((k, v) for k, v in found.items() if k not in ("algorithm", "hyperparameters"))
        return data


@dataclass(frozen=True)
class SweepResult:
    """Every grid point's outcome; `interrupted` when stopped early; `group` the first run's id."""

    spec: SweepSpec
    points: tuple[SweepPoint, ...]
    interrupted: bool
    group: int | None
    game: str
    optimum: float | None = None
    hyperparameters: Mapping[str, Any] = field(default_factory=dict)
    tasks: Mapping[str, int] = field(default_factory=dict)  # "done" and "total"

    @property
    def grid(self) -> dict[str, list[Any]]:
        """Each key's values as the hyperparameters read them, in the order given."""
        return {k: list(dict.fromkeys(p.values[k] for p in self.points)) for k in self.spec.keys}

    def ranked(self) -> list[SweepPoint]:
        """The points best first (those without a figure last, in their order)."""
        return sorted(self.points, key=lambda p: (p.rank is None, p.rank or 0))

    def to_json(self) -> dict[str, Any]:
        spec = self.spec
        return dict(plain({
            "game": self.game, "algorithm": spec.algorithm, "episodes": spec.episodes,
            "seeds": spec.seeds, "first_seed": spec.first_seed, "grid": self.grid,
            "sample": None if not spec.ranges else {
                "n": spec.samples, "seed": spec.sample_seed, "ranges": spec.ranges},
            "tasks": self.tasks, "hyperparameters": self.hyperparameters,
            "optimum": self.optimum, "interrupted": self.interrupted, "group": self.group,
            "points": self.points}))


def run_sweep(
    spec: SweepSpec, *, progress: Callable[[CompareProgress], None] | None = None,
    stop: threading.Event | None = None, history: RunHistory | None = None,
    processes: int | None = None, status: Callable[[str], None] | None = None,
    resume: int | None = None, cluster: Any = None,
) -> SweepResult:
    """Run a sweep (see the module docstring); arguments as `run_compare`'s."""
    setup = Setup(spec.game, spec.seeds, spec.episodes, spec.game_params,
                  tuple(spec.wrappers), spec.first_seed)
    points = spec.points()
    arms = [Arm(spec.algorithm, {**spec.settings, **values},
                ", ".join(f"{k}={v}" for k, v in values.items()))
            for values in points]
    done = execute(setup, arms, RunKind.SWEEP, progress=progress, stop=stop,
                   history=history, processes=processes, status=status, resume=resume,
                   cluster=cluster)
    hps = done.prepared.hyperparameters
    fixed = {k: v for k, v in hps[0].items() if k not in spec.keys}
    found = [SweepPoint({k: hp[k] for k in spec.keys}, o)
             for hp, o in zip(hps, done.outcomes, strict=True)]
    lowest = issubclass(algorithm(spec.algorithm), Predictor)  # an RMS error
    order = sorted((i for i, p in enumerate(found) if p.figure is not None),
                   key=lambda i: (found[i].figure or 0.0) * (1 if lowest else -1))
    for rank, i in enumerate(order, start=1):
        found[i] = replace(found[i], rank=rank)
    return SweepResult(
        spec=spec, points=tuple(found), tasks=done.tasks, interrupted=done.interrupted,
        group=done.group, game=done.prepared.game, optimum=done.prepared.optimum,
        hyperparameters=fixed,
    )
