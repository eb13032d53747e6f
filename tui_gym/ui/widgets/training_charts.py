"""`TrainingCharts`: learning curves (return, length, |TD error|, epsilon) as labelled
sparklines whose columns and ranges agree with the numbers written beside them."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from rich.color import Color as RichColor
from rich.color import blend_rgb
from rich.segment import Segment
from rich.style import Style

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.ui.widgets.numbers import fit, number_forms
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, component_classes, panel_css

BARS = "▁▂▃▄▅▆▇█"
NAME_WIDTH, VALUE_WIDTH, RANGE_WIDTH = 12, 9, 13
MIN_SPARK = 10  # narrower than this, the ranges make way for the curves
COLOUR_STEPS = 32  # bar colours are blended in this many steps


@dataclass(frozen=True)
class Curve:
    """One chart: which series, its name, and how its numbers read."""

    key: str  # key in TrainingSnapshot.series
    name: str
    current: Callable[[TrainingSnapshot], float]
    spec: str  # the format of its numbers
    of_episodes: bool = True  # the current value is a mean over recorded episodes


CURVES: tuple[Curve, ...] = (
    Curve("return", "mean return", lambda s: s.mean_return, "+.3f"),
    Curve("length", "ep. length", lambda s: s.mean_length, ".2f"),
    Curve("td_error", "mean |TD|", lambda s: s.mean_abs_td, ".4f"),
    Curve("epsilon", "epsilon", lambda s: s.epsilon, ".3f", of_episodes=False),
)


def bucket_means(data: Sequence[float], width: int) -> list[float]:
    """`width` values summarising `data`: bucket means, or samples when data is short."""
    n = len(data)
    if n == 0 or width <= 0:
        return []
    edges = np.arange(width + 1) * n // width
    if n < width:
        return [float(data[i]) for i in edges[:-1]]
    sums = np.concatenate(([0.0], np.cumsum(data)))
    return ((sums[edges[1:]] - sums[edges[:-1]]) / np.diff(edges)).tolist()


def plotted(data: Sequence[float], width: int, current: float | None = None) -> list[float]:
    """The `width` values a sparkline of `data` draws: bucket means of the series,
    the last column being `current` (the value shown beside the curve) when given."""
    if not data or width <= 0:
        return []
    if current is None:
        return bucket_means(data, width)
    return [*bucket_means(data, width - 1), float(current)]


def sparkline_rows(
    data: Sequence[float],
    width: int,
    height: int,
    low: RichColor,
    high: RichColor,
    *,
    flat: bool = False,
) -> list[Line]:
    """A sparkline of `data` (bucketed unless it has `width` values) in `width` x `height`
    cells, as lines of segments, top first; `flat`: a level line (a range too small to show)."""
    if not data:
        blank = [[Segment(" " * width)] for _ in range(height - 1)]
        return [*blank, [Segment("▁" * width, Style(color=low))]]
    values = list(data) if len(data) == width else bucket_means(data, width)
    lo, hi = min(values), max(values)
    extent = 0.0 if flat else hi - lo
    levels = len(BARS) * height - 1
    styles: dict[int, Style] = {}
    cells: list[tuple[int, Style]] = []  # (eighths filled, style) per column
    for value in values:
        ratio = (value - lo) / extent if extent else 0.5  # a flat curve: a level line
        step = round(ratio * COLOUR_STEPS)
        style = styles.get(step)
        if style is None:
            style = Style(color=mix(low, high, step / COLOUR_STEPS))
            styles[step] = style
        cells.append((int(ratio * levels), style))
    rows: list[Line] = []
    for row in reversed(range(height)):
        floor, top = row * len(BARS), (row + 1) * len(BARS)
        line: Line = []
        for filled, style in cells:
            if filled < floor:
                glyph, glyph_style = " ", None
            elif filled >= top:
                glyph, glyph_style = "█", style
            else:
                glyph, glyph_style = BARS[filled - floor], style
            if line and line[-1].style is glyph_style:
                line[-1] = Segment(line[-1].text + glyph, glyph_style)
            else:
                line.append(Segment(glyph, glyph_style))
        rows.append(line)
    return rows


def mix(a: RichColor, b: RichColor, t: float) -> RichColor:
    """`a` moved a share `t` of the way to `b`."""
    return RichColor.from_triplet(blend_rgb(a.get_truecolor(), b.get_truecolor(), t))


class TrainingCharts(StripWidget):
    """Four sparklines with names, current values and ranges."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = panel_css("TrainingCharts") + """
    TrainingCharts > .charts--name { color: $text-muted; }
    TrainingCharts > .charts--value { text-style: bold; }
    TrainingCharts > .charts--range { color: $text-disabled; }
    TrainingCharts > .charts--return-high { color: $success; }
    TrainingCharts > .charts--return-low { color: $error 70%; }
    TrainingCharts > .charts--length-high { color: $accent; }
    TrainingCharts > .charts--length-low { color: $accent 40%; }
    TrainingCharts > .charts--td_error-high { color: $error; }
    TrainingCharts > .charts--td_error-low { color: $error 40%; }
    TrainingCharts > .charts--epsilon-high { color: $primary; }
    TrainingCharts > .charts--epsilon-low { color: $primary 40%; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._data: dict[str, tuple[float, ...]] = {}
        self._values: dict[str, str] = {}
        self._current: dict[str, float | None] = {}
        self.border_title = "Learning curves"

    # --- data in -----------------------------------------------------------
    def data(self, key: str) -> tuple[float, ...]:
        """The series one sparkline draws ("return", "length", "td_error", "epsilon")."""
        return self._data.get(key, ())

    def value_text(self, key: str) -> str:
        """The current value shown beside a sparkline (in its fullest form)."""
        return self._values.get(key, "")

    def plotted(self, key: str, width: int) -> list[float]:
        """The columns one sparkline draws at a given width (see `plotted`)."""
        return plotted(self._data.get(key, ()), width, self._current.get(key))

    def clear(self) -> None:
        """Forget every curve (after an agent reset)."""
        self._data.clear()
        self._values.clear()
        self._current.clear()
        self.border_subtitle = ""
        self.redraw()

    def update_from(self, snapshot: TrainingSnapshot) -> None:
        """Show a snapshot's curves; nothing is drawn when nothing changed."""
        recorded = snapshot.recorded  # episodes in the statistics (none just after a load)
        window = min(snapshot.window, max(1, recorded))
        # Below the box: at animated speeds the board beside it leaves the title little room.
        subtitle = f"rolling mean of {window:,}" if recorded else ""
        if subtitle != self.border_subtitle:
            self.border_subtitle = subtitle
        changed = False
        for curve in CURVES:
            key = curve.key
            data = tuple(snapshot.series.get(key, ())) if recorded else ()
            current = curve.current(snapshot) if recorded or not curve.of_episodes else None
            text = format(current, curve.spec) if current is not None else "–"
            if self._data.get(key) != data or self._values.get(key) != text:
                self._data[key], self._values[key] = data, text
                self._current[key] = current
                changed = True
        if changed:
            self.redraw()

    # --- drawing -----------------------------------------------------------
    def draw(self, width: int) -> list[Line]:
        compact = self._compact()
        height = 1 if compact else 2
        styles = self.component_styles()
        name_style, value_style = styles["charts--name"], styles["charts--value"]
        range_style = styles["charts--range"]
        range_width = 0 if compact else RANGE_WIDTH + 1
        if width - NAME_WIDTH - VALUE_WIDTH - 2 - range_width < MIN_SPARK:
            range_width = 0  # a narrow box (the board beside it): the curves, not their ranges
        spark_width = max(1, width - NAME_WIDTH - VALUE_WIDTH - 2 - range_width)
        lines: list[Line] = []
        for curve in CURVES:
            current = self._current.get(curve.key)
            columns = plotted(self._data.get(curve.key, ()), spark_width, current)
            low = styles[f"charts--{curve.key}-low"].color or RichColor.default()
            high = styles[f"charts--{curve.key}-high"].color or RichColor.default()
            value = "–" if current is None else fit(number_forms(current, curve.spec), VALUE_WIDTH)
            ends, flat = ["", ""], False
            if columns:
                top = fit(number_forms(max(columns), curve.spec), RANGE_WIDTH - 4)
                bottom = fit(number_forms(min(columns), curve.spec), RANGE_WIDTH - 4)
                ends, flat = [f"max {top}", f"min {bottom}"], top == bottom
            spark = sparkline_rows(columns, spark_width, height, low, high, flat=flat)
            for row in range(height):
                line: Line = [
                    *_cell(curve.name if row == 0 else "", NAME_WIDTH, name_style),
                    *_cell(value if row == 0 else "", VALUE_WIDTH, value_style, right=True),
                    Segment(" "),
                    *spark[row],
                    Segment(" "),
                ]
                if range_width:
                    line += _cell(ends[row], range_width, range_style, right=True)
                lines.append(line)
        return lines


def _cell(text: str, width: int, style: Style, right: bool = False) -> Line:
    """`text` in a column `width` cells wide, the padding left unstyled."""
    text = text[:width]
    pad = Segment(" " * (width - len(text)))
    body = Segment(text, style)
    return [pad, body] if right else [body, pad]


__all__ = ["CURVES", "Curve", "TrainingCharts", "bucket_means", "plotted", "sparkline_rows"]
