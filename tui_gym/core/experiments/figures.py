"""`Figure`: one named, typed result (a value, its unit, and its 95% interval when it has
one); `FieldsJson`: a result whose JSON is its fields'."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any


def plain(value: Any) -> Any:
    """`value` as JSON data: results by `to_json`, paths as text, tuples as lists, NaN as null."""
    if hasattr(value, "to_json"):
        return value.to_json()
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, tuple | list):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class FieldsJson:
    """A dataclass whose JSON is its fields by name, each as `plain` gives it."""

    def to_json(self) -> dict[str, Any]:
        return {f.name: plain(getattr(self, f.name)) for f in fields(self)}  # type: ignore[arg-type]


@dataclass(frozen=True)
class Figure(FieldsJson):
    """A named result: `value` in `unit`, with the half-width of its 95% interval if known."""

    name: str
    value: float
    unit: str = ""
    ci95: float | None = None

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("a figure needs a name")
        object.__setattr__(self, "value", float(self.value))
        if self.ci95 is not None:
            object.__setattr__(self, "ci95", float(self.ci95))
