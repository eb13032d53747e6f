"""Line charts with confidence bands in the terminal, for `compare` and `sweep`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from rich.text import Text

PALETTE = ("cyan", "magenta", "yellow", "green", "red", "blue", "bright_white", "bright_cyan")
BAND = "░"
BRAILLE_BASE = 0x2800
# The braille dot bit at (row 0..3 from the top, column 0..1) of a character cell.
DOT_BITS = np.array(((0x01, 0x08), (0x02, 0x10), (0x04, 0x20), (0x40, 0x80)))


@dataclass(frozen=True, eq=False)
class ChartSeries:
    """One curve: its name, x values, means and band edges (None for no band)."""

    name: str
    x: np.ndarray
    mean: np.ndarray
    lo: np.ndarray | None = None
    hi: np.ndarray | None = None


def format_number(value: float) -> str:
    """A short form of an axis value."""
    if not math.isfinite(value):
        return str(value)
    if value != 0 and (abs(value) >= 1e5 or abs(value) < 1e-3):
        return f"{value:.2g}"
    if abs(value) >= 100:
        return f"{value:.0f}"
    return f"{value:.3g}"


def spans(first: np.ndarray, last: np.ndarray, rows: int) -> np.ndarray:
    """A (rows, columns) mask: column c holds rows first[c] to last[c] (none if first > last)."""
    row = np.arange(rows)[:, None]
    return (row >= first) & (row <= last)


def curve_bits(rows: np.ndarray, height: int, inside: np.ndarray | None = None, *,
               halfway: bool = False) -> np.ndarray:
    """The braille bits of `height` rows of cells drawing a curve at dot row rows[x] in each
    dot column x (those `inside`; by default all), each dot joined by a run to the one
    before it: from just past it, or (`halfway`) over the nearer half of the step."""
    inside = np.ones(len(rows), dtype=bool) if inside is None else inside
    row = rows[inside]
    previous = np.concatenate((row[:1], row[:-1]))
    middle = (previous + row) // 2
    top, bottom = np.full(len(rows), 4 * height), np.full(len(rows), -1)
    top[inside] = np.where(row > previous, middle + 1 if halfway else previous + 1, row)
    bottom[inside] = np.where(row < previous, middle if halfway else previous - 1, row)
    inked = spans(top, bottom, 4 * height).reshape(height, 4, len(rows) // 2, 2)
    return (inked * DOT_BITS[:, None, :]).sum(axis=(1, 3))


def _binned(x: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The mean of `values` in each x bin; an empty bin takes the value of the bin before
    it (or after, at the start)."""
    x, values = np.asarray(x, dtype=np.float64), np.asarray(values, dtype=np.float64)
    index = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    sums = np.bincount(index, weights=values, minlength=len(edges) - 1)
    counts = np.bincount(index, minlength=len(edges) - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(counts > 0, sums / counts, np.nan)
    present = ~np.isnan(means)
    if not present.any():
        return means
    before = np.maximum.accumulate(np.where(present, np.arange(len(means)), -1))
    return means[np.where(before < 0, np.argmax(present), before)]


def band_chart(
    series: Sequence[ChartSeries], width: int = 72, height: int = 16, *, x_label: str = "episode",
    y_label: str = "", skip_start: bool = False,
) -> Text:
    """The chart of `series` in `width` x `height` character cells of plot, plus axes and legend
    (with `skip_start` the y range fits the curves after their first 5%; points beyond it sit
    on its edge, as the legend says)."""
    shown = [s for s in series if len(s.x)]
    if not shown:
        return Text("(nothing to plot yet)")
    width, height = max(8, width), max(3, height)
    x_min = float(min(s.x.min() for s in shown))
    x_max = float(max(s.x.max() for s in shown))
    if x_max == x_min:
        x_max = x_min + 1
    columns, rows = 2 * width, 4 * height
    edges = np.linspace(x_min, x_max, columns + 1)
    edges[-1] = np.nextafter(edges[-1], np.inf)
    binned = []
    for s in shown:
        lo, hi = ((_binned(s.x, s.lo, edges), _binned(s.x, s.hi, edges))
                  if s.lo is not None and s.hi is not None else (None, None))
        binned.append((_binned(s.x, s.mean, edges), lo, hi))
    # The y range leaves out the first columns when they alone would stretch it (early
    # learning curves start far below where they end): those points sit on the edge.
    skip = columns // 20 if skip_start else 0
    arrays = [a for b in binned for a in b if a is not None]
    fitted, whole = (np.concatenate(parts) for parts in ([a[skip:] for a in arrays], arrays))
    fitted, whole = fitted[np.isfinite(fitted)], whole[np.isfinite(whole)]
    y_min, y_max = (float(fitted.min()), float(fitted.max())) if fitted.size else (0, 1)
    clipped = bool(whole.size) and (whole.min() < y_min or whole.max() > y_max)
    if y_max == y_min:
        y_min, y_max = y_min - 1, y_max + 1

    def dot_row(y: np.ndarray) -> np.ndarray:
        scaled = (y_max - y) / (y_max - y_min) * (rows - 1)
        return np.clip(np.rint(np.nan_to_num(scaled, nan=rows - 1)), 0, rows - 1).astype(int)

    dots = np.zeros((height, width), dtype=np.int64)
    dot_owner = np.full((height, width), -1, dtype=np.int64)
    band_owner = np.full((height, width), -1, dtype=np.int64)
    for k, (mean, lo, hi) in enumerate(binned):
        if lo is not None and hi is not None:
            top, bottom = dot_row(hi).reshape(width, 2), dot_row(lo).reshape(width, 2)
            band_owner[spans(top.min(axis=1) // 4, bottom.max(axis=1) // 4, height)] = k
        # Each dot is joined to the one before it, so that steep stretches stay one line.
        drawn = curve_bits(dot_row(mean), height, halfway=True)
        dots |= drawn
        dot_owner[drawn > 0] = k
    labels = [format_number(y_max), format_number((y_max + y_min) / 2), format_number(y_min)]
    pad = max(len(label) for label in labels)
    text = Text()
    if y_label:
        text.append(f"{y_label}\n", style="bold")
    at_row = {0: labels[0], height // 2: labels[1], height - 1: labels[2]}  # height >= 3
    for r in range(height):
        label = at_row.get(r, "")
        text.append(f"{label:>{pad}} ┤" if label else f"{'':>{pad}} │", style="dim")
        for c in range(width):
            owner = int(dot_owner[r, c])
            if owner >= 0:
                text.append(chr(BRAILLE_BASE + int(dots[r, c])), style=f"bold {_colour(owner)}")
            elif band_owner[r, c] >= 0:
                text.append(BAND, style=_colour(int(band_owner[r, c])))
            else:
                text.append(" ")
        text.append("\n")
    axis = f"{'':>{pad}} └" + "─" * width
    text.append(axis + "\n", style="dim")
    left, right = format_number(x_min), format_number(x_max)
    gap = max(1, width - len(left) - len(right))
    text.append(f"{'':>{pad}}  {left}{' ' * gap}{right}\n", style="dim")
    if x_label:
        text.append(f"{'':>{pad}}  {x_label:^{width}}\n", style="dim")
    text.append(f"{'':>{pad}}  ")
    for k, s in enumerate(shown):
        text.append("━━ ", style=f"bold {_colour(k)}")
        text.append(s.name)
        text.append("   ")
    if any(lo is not None for _, lo, _ in binned):
        text.append(f"{BAND * 2} 95% band", style="dim")
    if clipped:
        note = "(the first episodes go off the scale: drawn on its edge)"
        text.append("\n" + " " * (pad + 2) + note, style="dim")
    return text


def _colour(k: int) -> str:
    return PALETTE[k % len(PALETTE)]
