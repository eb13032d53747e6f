"""`Heatmap`: one panel of a Q-table projected onto a grid, as plain data the UI colours."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Heatmap:
    """One panel of cells: value per cell, a short label, and a mark for notable cells."""

    title: str
    row_labels: tuple[str, ...]  # top to bottom
    col_labels: tuple[str, ...]  # left to right
    values: np.ndarray  # (rows, cols) float; NaN where there is no state
    labels: tuple[tuple[str, ...], ...]  # (rows, cols) text drawn in each cell
    marked: np.ndarray  # (rows, cols) bool: e.g. differs from the optimum
    legend: str = ""

    @property
    def shape(self) -> tuple[int, int]:
        return self.values.shape  # type: ignore[return-value]

    def value_range(self) -> tuple[float, float]:
        finite = self.values[np.isfinite(self.values)]
        if finite.size == 0:
            return (0.0, 0.0)
        return float(finite.min()), float(finite.max())
