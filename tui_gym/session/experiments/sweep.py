"""Sweeps: one algorithm over a grid of hyperparameter values, each point over many seeds.

`run_sweep(SweepSpec(...))` trains the algorithm at every point of the grid
(the product of each key's values, the first key slowest) exactly as a
comparison trains its algorithms (`compare.execute`: every seed a learner of
its own, spread over child processes when the work is long), and returns a
`SweepResult` with one `SweepPoint` per grid point: its values and its
`AlgorithmOutcome`. With a `RunHistory` each
point is recorded as one run of kind `sweep`, grouped as a comparison's are.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from tui_gym.algorithms import algorithm
from tui_gym.core.experiments.history import RunHistory
from tui_gym.core.experiments.records import RunKind
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.experiments.compare import (
    AlgorithmOutcome,
    Arm,
    CompareProgress,
    Setup,
    _finite,
    execute,
)

__all__ = ["SWEEP_CURVE_POINTS", "SweepPoint", "SweepResult", "SweepSpec", "run_sweep"]

SWEEP_CURVE_POINTS = 100  # curve points per grid point in `to_json`
MAX_POINTS = 400  # grid points in one sweep at most


@dataclass(frozen=True)
class SweepSpec:
    """`algorithm` on `game` at every point of `grid` (key -> values), `seeds` seeds each.

    `settings` are fixed values for the other hyperparameters."""

    game: str
    algorithm: str
    grid: Mapping[str, Sequence[Any]]
    seeds: int
    episodes: int
    settings: Mapping[str, Any] = field(default_factory=dict)
    game_params: Mapping[str, Any] = field(default_factory=dict)
    wrappers: Sequence[WrapperChoice] = ()
    first_seed: int = 0

    def __post_init__(self) -> None:
        cls = algorithm(self.algorithm)
        object.__setattr__(self, "algorithm", cls.name)
        grid = {str(k): tuple(v) for k, v in self.grid.items()}
        if not grid:
            raise ValueError("a sweep needs at least one --grid KEY=V1,V2")
        fields = {f.name for f in cls.params}
        for key, values in grid.items():
            if key not in fields:
                raise ValueError(
                    f"{cls.name} has no hyperparameter {key!r}; it has {', '.join(sorted(fields))}"
                )
            if not values:
                raise ValueError(f"--grid {key}: give at least one value")
            if len(set(map(str, values))) != len(values):
                raise ValueError(f"--grid {key}: a value is listed twice")
        for key in self.settings:
            if key in grid:
                raise ValueError(f"{key} is both swept and set")
            if key not in fields:
                raise ValueError(f"{cls.name} has no hyperparameter {key!r}")
        count = 1
        for values in grid.values():
            count *= len(values)
        if count > MAX_POINTS:
            raise ValueError(f"the grid has {count} points; at most {MAX_POINTS} at once")
        for name, value in (("seeds", self.seeds), ("episodes", self.episodes)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        object.__setattr__(self, "grid", grid)
        object.__setattr__(self, "settings", dict(self.settings))
        object.__setattr__(self, "game_params", dict(self.game_params))
        object.__setattr__(self, "wrappers", tuple(self.wrappers))

    def points(self) -> list[dict[str, Any]]:
        """Every grid point as {key: value}, the first key's values slowest."""
        keys = list(self.grid)
        return [dict(zip(keys, combo, strict=True))
                for combo in itertools.product(*self.grid.values())]


@dataclass(frozen=True)
class SweepPoint:
    """One grid point: its values (as the hyperparameters read them) and its outcome."""

    values: Mapping[str, Any]
    outcome: AlgorithmOutcome | None

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"values": dict(self.values)}
        o = self.outcome
        if o is None:
            data.update(seeds_done=0, episodes_done=0, mean_return_last=None, ci95=None,
                        exact_value=None, exact_gap=None, run_id=None, curve=[])
            return data
        data.update(
            seeds_done=o.seeds_done,
            episodes_done=o.episodes,
            mean_return_last=_finite(o.mean_return_last.mean),
            ci95=o.mean_return_last.ci95,
            exact_value=_finite(o.exact_value),
            exact_gap=_finite(o.exact_gap),
            run_id=o.run_id,
            curve=[p.to_json() for p in o.curve.downsample(SWEEP_CURVE_POINTS).points()],
        )
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

    @property
    def grid(self) -> dict[str, list[Any]]:
        """Each key's values as the hyperparameters read them, in the order given."""
        keys = list(self.spec.grid)
        return {k: list(dict.fromkeys(p.values[k] for p in self.points)) for k in keys}

    def to_json(self) -> dict[str, Any]:
        spec = self.spec
        return {
            "game": self.game,
            "algorithm": spec.algorithm,
            "episodes": spec.episodes,
            "seeds": spec.seeds,
            "first_seed": spec.first_seed,
            "grid": self.grid,
            "hyperparameters": dict(self.hyperparameters),
            "optimum": _finite(self.optimum),
            "interrupted": self.interrupted,
            "group": self.group,
            "points": [p.to_json() for p in self.points],
        }


def run_sweep(
    spec: SweepSpec,
    *,
    progress: Callable[[CompareProgress], None] | None = None,
    stop: threading.Event | None = None,
    history: RunHistory | None = None,
    processes: int | None = None,
    status: Callable[[str], None] | None = None,
) -> SweepResult:
    """Run a sweep (see the module docstring); arguments as `run_compare`'s."""
    setup = Setup(spec.game, spec.seeds, spec.episodes, spec.game_params,
                  tuple(spec.wrappers), spec.first_seed)
    points = spec.points()
    arms = [Arm(spec.algorithm, {**spec.settings, **values},
                ", ".join(f"{k}={v}" for k, v in values.items()))
            for values in points]
    done = execute(setup, arms, RunKind.SWEEP, progress=progress, stop=stop,
                   history=history, processes=processes, status=status)
    hps = done.prepared.hyperparameters
    swept = [{k: hp[k] for k in spec.grid} for hp in hps]
    fixed = {k: v for k, v in hps[0].items() if k not in spec.grid}
    return SweepResult(
        spec=spec,
        points=tuple(SweepPoint(v, o) for v, o in zip(swept, done.outcomes, strict=True)),
        interrupted=done.interrupted,
        group=done.group,
        game=done.prepared.game,
        optimum=done.prepared.optimum,
        hyperparameters=fixed,
    )
