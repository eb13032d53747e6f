"""A run's finished tasks as the run history keeps them: `TaskRecord`, its row and back."""

from __future__ import annotations

import json
import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tui_gym.core.experiments.records import to_json_text

MAX_TASK_BYTES = 64 * 1024 * 1024  # what one task's arrays may take once decompressed
LEVEL = 1  # zlib's quickest: several times quicker than its default, nearly as small


class BadTask(ValueError):
    """A stored task that does not read as what tui-gym writes."""


@dataclass(frozen=True, eq=False)
class TaskRecord:
    """A finished task: seeds `seeds` (rows `rows` of the run's seed list), `episodes`
    each; `returns[i, e]` seed i's online return in episode e; `exact[i, j]` its greedy
    policy's exact value at checkpoint j, a prediction learner's RMS error of V (None
    without a model)."""

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


def encode(task: TaskRecord) -> tuple[int, str, bytes, bytes | None]:
    """The row's first row, inputs, returns and exact values."""
    returns = np.ascontiguousarray(task.returns, dtype="<f8")
    if returns.shape != (len(task.rows), task.episodes) or len(task.seeds) != len(task.rows):
        raise ValueError("a task's returns must be one row of `episodes` per seed")
    exact = None
    if task.exact is not None:
        exact = zlib.compress(np.ascontiguousarray(task.exact, dtype="<f8").tobytes(), LEVEL)
    return (min(task.rows), to_json_text(task.inputs(), "a task's inputs"),
            zlib.compress(returns.tobytes(), LEVEL), exact)


def _array(blob: object, shape: tuple[int, int], what: str) -> np.ndarray:
    if not isinstance(blob, bytes):
        raise BadTask(f"its {what} are not a blob")
    try:
        inflate = zlib.decompressobj()
        data = inflate.decompress(blob, MAX_TASK_BYTES + 1)
    except zlib.error:
        raise BadTask(f"its {what} do not decompress") from None
    if len(data) != shape[0] * shape[1] * 8 or inflate.unconsumed_tail:
        raise BadTask(f"its {what} are not {shape[0]} × {shape[1]} numbers")
    return np.frombuffer(data, dtype="<f8").reshape(shape).astype(np.float64)


def _ints(value: object, what: str) -> tuple[int, ...]:
    if not isinstance(value, list) or not value or not all(
            isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in value):
        raise BadTask(f"its {what} are not a list of whole numbers")
    return tuple(value)


def decode_rows(inputs: object) -> tuple[int, ...]:
    """The rows a stored task's inputs name; BadTask if they do not read."""
    return _ints(_inputs(inputs).get("rows"), "rows")


def _inputs(inputs: object) -> dict[str, Any]:
    try:
        data = json.loads(inputs) if isinstance(inputs, str) else None
    except ValueError:
        data = None
    if not isinstance(data, dict):
        raise BadTask("its inputs are not a JSON object")
    return data


def decode(inputs: object, returns: object, exact: object) -> TaskRecord:
    """A stored task's row as a `TaskRecord`; BadTask if it does not read."""
    data = _inputs(inputs)
    rows, seeds = _ints(data.get("rows"), "rows"), _ints(data.get("seeds"), "seeds")
    episodes, checkpoints = data.get("episodes"), data.get("checkpoints")
    if len(rows) != len(seeds) or not isinstance(episodes, int) or episodes < 1:
        raise BadTask("its seeds, rows and episodes do not agree")
    hp = data.get("hyperparameters")
    if not isinstance(hp, dict) or not isinstance(data.get("algorithm"), str):
        raise BadTask("its algorithm or hyperparameters do not read")
    table = None
    if checkpoints is not None:
        if not isinstance(checkpoints, int) or checkpoints < 0:
            raise BadTask("its count of checkpoints is not a whole number")
        table = _array(exact, (len(rows), checkpoints), "exact values")
    return TaskRecord(rows, seeds, episodes, _array(returns, (len(rows), episodes), "returns"),
                      table, data["algorithm"], hp)
