"""Small helpers the benchmarks share: medians, percentiles, timing, child processes, the
machine's load."""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

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


def timed(run: Callable[[], Any], repeats: int = 1) -> tuple[float, Any]:
    """The median seconds of `repeats` runs, and the last run's result."""
    times, result = [], None
    for _ in range(repeats):
        began = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - began)
    return median(times), result


def child_json(module: str, *args: str, what: str, timeout: float, stdin: str | None = None,
               env: dict[str, str] | None = None) -> Any:
    """Run `python -m module args` in a fresh interpreter; the JSON of its last output line
    (RuntimeError saying `what` failed, and the end of its stderr, when it fails)."""
    done = subprocess.run([sys.executable, "-m", module, *args], input=stdin,
                          capture_output=True, text=True, env={**os.environ, **(env or {})},
                          timeout=timeout, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{what} failed: {done.stderr.strip()[-300:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def load_average() -> tuple[float, float, float] | None:
    """The 1, 5 and 15 minute load averages, where the OS tells them."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return None
