"""`Figure`: one named, typed result (a value, its unit, and its 95% interval when it has one)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Figure:
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

    def to_json(self) -> dict[str, Any]:
        """The figure as JSON data (NaN, which JSON cannot hold, as null)."""
        return {
            "name": self.name, "value": self.value if math.isfinite(self.value) else None,
            "unit": self.unit, "ci95": self.ci95,
        }
