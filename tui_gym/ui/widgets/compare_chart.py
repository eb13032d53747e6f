"""`CompareChart`: several return curves overlaid, each with its 95% band, a legend and colours."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from typing import ClassVar

import numpy as np
from rich.color import Color as RichColor
from rich.segment import Segment
from rich.style import Style

from tui_gym.terminal_chart import BRAILLE_BASE, curve_bits, spans
from tui_gym.ui.compare_series import Series
from tui_gym.ui.widgets.numbers import fit, number_forms
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, panel_css
from tui_gym.ui.widgets.training_charts import mix

# Distinct on dark and light themes alike; a curve keeps its colour while it is shown.
PALETTE: tuple[str, ...] = (
    "#3d9df3", "#f5a030", "#3cc46a", "#e5484d", "#a77bf0", "#e0c43a", "#2fc5c0", "#f06bab",
)
# The y axis leaves out the first tenth of the episodes: a learner's first episodes (a
# random walk that takes 1,000 steps) would squeeze the rest into a line, as Sutton &
# Barto's figures clip them.
EARLY_SHARE = 0.1
BAND_TINT = 0.28  # how much of a curve's colour its band mixes into the background
LABEL_WIDTH = 8  # the y labels' column, with a space after it
PLOT_HEIGHT, COMPACT_PLOT_HEIGHT = 12, 7  # lines of the plot
EMPTY = "Tick runs in the list to draw their return curves here."


def colour(index: int) -> RichColor:
    """The palette's colour for a curve's place (it wraps round after eight)."""
    return RichColor.parse(PALETTE[index % len(PALETTE)])


def value_range(series: Sequence[Series]) -> tuple[float, float]:
    """The y range the curves and bands fit in past the first `EARLY_SHARE` of the
    episodes (widened when it is a single value, never past the returns the games
    allow when every curve knows them); what lies outside is drawn at the edge."""
    first, last = episode_range(series)
    start = first + EARLY_SHARE * (last - first)
    lows, highs = [], []
    for s in series:
        keep = s.episodes >= start
        if not keep.any():
            keep = np.ones(len(s.episodes), dtype=bool)
        lows.append(float(np.min((s.lo if s.lo is not None else s.mean)[keep])))
        highs.append(float(np.max((s.hi if s.hi is not None else s.mean)[keep])))
    low, high = min(lows), max(highs)
    if high - low < 1e-12:
        pad = max(0.5, abs(low) * 0.1)
        low, high = low - pad, high + pad
        bounds = [s.bounds for s in series if s.bounds is not None]
        if len(bounds) == len(series):
            low, high = max(low, min(b[0] for b in bounds)), min(high, max(b[1] for b in bounds))
        if high - low < 1e-12:  # the games allow this one return only
            low, high = low - pad, high + pad
    return low, high


def episode_range(series: Sequence[Series]) -> tuple[int, int]:
    first = min(int(s.episodes[0]) for s in series)
    last = max(int(s.episodes[-1]) for s in series)
    return first, max(last, first + 1)


def plot_cells(
    series: Sequence[Series], width: int, height: int
) -> tuple[list[list[int]], list[list[int]], list[list[int]]]:
    """The plot as three grids of `height` x `width` cells: braille bits, the index of the
    curve whose dot was drawn last (-1: none) and the bands that shade it (a bit per curve,
    1 << index; 0: none)."""
    bits = np.zeros((max(0, height), max(0, width)), dtype=np.int64)
    ink = np.full(bits.shape, -1)
    band = np.zeros(bits.shape, dtype=object)  # Python ints: a bit for every curve
    if not series or width < 1 or height < 1:
        return bits.tolist(), ink.tolist(), band.tolist()
    low, high = value_range(series)
    first, last = episode_range(series)
    span = high - low

    def cell_row(values: np.ndarray) -> np.ndarray:
        return np.clip(np.trunc((high - values) / span * height), 0, height - 1).astype(int)

    centres = first + (np.arange(width) + 0.5) / width * (last - first)
    for index, s in enumerate(series):
        if s.lo is None or s.hi is None:
            continue
        inside = (centres >= s.episodes[0]) & (centres <= s.episodes[-1])
        tops = np.where(inside, cell_row(np.interp(centres, s.episodes, s.hi)), height)
        band[spans(tops, cell_row(np.interp(centres, s.episodes, s.lo)), height)] |= 1 << index
    dots_x, dots_y = 2 * width, 4 * height
    xs = first + np.arange(dots_x) / max(1, dots_x - 1) * (last - first)
    for index, s in enumerate(series):
        inside = (xs >= s.episodes[0] - 1e-9) & (xs <= s.episodes[-1] + 1e-9)
        if len(s.episodes) == 1:  # one point: a dot at its episode
            inside = np.zeros(dots_x, dtype=bool)
            inside[int(round((s.episodes[0] - first) / (last - first) * (dots_x - 1)))] = True
        values = np.interp(xs, s.episodes, s.mean)
        rows = np.clip(np.rint((high - values) / span * (dots_y - 1)), 0, dots_y - 1).astype(int)
        drawn = curve_bits(rows, height, inside)
        bits |= drawn
        ink[drawn > 0] = index
    return bits.tolist(), ink.tolist(), band.tolist()


class CompareChart(StripWidget):
    """Curves with bands, y and episode labels, and a legend (`show(series)`)."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    COMPONENT_CLASSES: ClassVar[set[str]] = {"chart--axis", "chart--empty"}
    DEFAULT_CSS = panel_css("CompareChart") + """
    CompareChart > .chart--axis { color: $text-muted; }
    CompareChart > .chart--empty { color: $text-muted; text-style: italic; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.series: tuple[Series, ...] = ()
        self.colours: tuple[int, ...] = ()  # each shown curve's place in the palette
        self.border_title = "Return per episode"

    def show(self, series: Sequence[Series], colours: Sequence[int] | None = None) -> None:
        """Draw these curves, each in its palette colour (by default, in order)."""
        series = tuple(series)
        colours = tuple(colours) if colours is not None else tuple(range(len(series)))
        if series != self.series or colours != self.colours:
            self.series, self.colours = series, colours
            self.redraw(layout=True)

    def draw(self, width: int) -> list[Line]:
        styles = self.component_styles()
        axis = styles["chart--axis"]
        if not self.series:
            return [[Segment(EMPTY[:width], styles["chart--empty"])]]
        height = COMPACT_PLOT_HEIGHT if self._compact() else PLOT_HEIGHT
        plot_width = max(1, width - LABEL_WIDTH)
        bits, ink, band = plot_cells(self.series, plot_width, height)
        low, high = value_range(self.series)
        background = self.rich_style.bgcolor or RichColor.parse("#000000")
        colours = [colour(c) for c in self.colours]
        line_styles = [Style(color=c) for c in colours]

        @cache
        def cell_style(ink: int, band: int) -> Style:
            fg = colours[ink] if ink >= 0 else None
            if not band:
                return Style(color=fg)
            # Where bands overlap, the tint of their colours' mean: each band stays visible.
            members = [c for i, c in enumerate(colours) if band >> i & 1]
            mean = members[0]
            for n, other in enumerate(members[1:], start=2):
                mean = mix(mean, other, 1 / n)
            return Style(color=fg, bgcolor=mix(background, mean, BAND_TINT))

        labels = {row: fit(number_forms(v, "+.3f"), LABEL_WIDTH - 1)
                  for row, v in ((0, high), (height // 2, (high + low) / 2), (height - 1, low))}
        lines: list[Line] = []
        for row in range(height):
            line: Line = [Segment(labels[row].rjust(LABEL_WIDTH - 1) + "┤"
                                  if row in labels else " " * (LABEL_WIDTH - 1) + "│", axis)]
            for col in range(plot_width):
                style = cell_style(ink[row][col], band[row][col])
                glyph = chr(BRAILLE_BASE + bits[row][col]) if bits[row][col] else " "
                # A dot is a segment of its own: an SVG viewer whose font draws braille
                # wider than a cell then still puts each dot in its cell, inside the box.
                before = line[-1]
                if before.style is style and glyph == " " == before.text[-1]:
                    line[-1] = Segment(before.text + glyph, style)
                else:
                    line.append(Segment(glyph, style))
            lines.append(line)
        first, last = episode_range(self.series)
        left, right = f"{first:,}", f"{last:,} episodes"
        gap = plot_width - len(left) - len(right)
        if gap < 1:
            right = f"{last:,}"
            gap = max(1, plot_width - len(left) - len(right))
        lines.append([Segment(" " * LABEL_WIDTH + left + " " * gap + right, axis)])
        for s, style in zip(self.series, line_styles, strict=True):
            lines.append([Segment("━━ ", style), Segment(s.legend()[: max(0, width - 3)])])
        return lines


__all__ = ["PALETTE", "CompareChart", "colour", "plot_cells", "value_range"]
