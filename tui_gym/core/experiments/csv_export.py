"""A run's curves as CSV: one row per episode that any curve has, one column per curve.

Floats are
written in full (`repr`), so reading them back gives the same numbers; an
episode a curve has no value at is an empty cell.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence

import numpy as np

from tui_gym.core.experiments.records import Curve

EPISODE_COLUMN = "episode"


def curves_csv(curves: Sequence[Curve]) -> tuple[str, int]:
    """The CSV text of `curves` and its number of data rows."""
    episodes = (
        np.unique(np.concatenate([c.episodes for c in curves]))
        if curves
        else np.empty(0, dtype=np.int64)
    )
    columns: list[list[str]] = []
    for curve in curves:
        cells = [""] * len(episodes)
        at = np.searchsorted(episodes, curve.episodes)
        for i, value in zip(at.tolist(), curve.values.tolist(), strict=True):
            cells[i] = "" if value != value else repr(value)  # NaN: no value here
        columns.append(cells)
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([EPISODE_COLUMN, *(c.name for c in curves)])
    for row, episode in enumerate(episodes.tolist()):
        writer.writerow([episode, *(cells[row] for cells in columns)])
    return out.getvalue(), len(episodes)
