"""Small helpers the benchmarks share: medians, percentiles, the machine's load.

Every figure `tui-gym bench` prints is a median over repeats, a percentile
over many samples, or a ratio of two figures measured in the same run.
"""

from __future__ import annotations

import os
import statistics
from collections.abc import Sequence

import numpy as np


def median(values: Sequence[float]) -> float:
    """The median (NaN for no values)."""
    return float(statistics.median(values)) if values else float("nan")


def percentile(values: Sequence[float], q: float) -> float:
    """The q-th percentile, linearly interpolated (NaN for no values)."""
    return float(np.percentile(np.asarray(values, dtype=np.float64), q)) if values else float("nan")


def ratio(numerator: float | None, denominator: float | None) -> float | None:
    """numerator / denominator, or None when either is missing or the denominator is 0."""
    if numerator is None or denominator is None or denominator == 0:
        return None
    return numerator / denominator


def load_average() -> tuple[float, float, float] | None:
    """The 1, 5 and 15 minute load averages, where the OS tells them."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return None
