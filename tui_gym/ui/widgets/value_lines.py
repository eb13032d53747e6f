"""`ValueLines`: values along one axis of states, drawn as the book draws the gambler's;
`BandCharts`, the base of widgets that draw two charts one above the other."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np
from rich.console import RenderableType
from rich.text import Text
from textual.widget import Widget

from tui_gym.terminal_chart import ChartSeries, band_chart

__all__ = ["BandCharts", "ValueLines"]

MARGIN = 12  # the y labels and the axis beside the plot
Chart = tuple[list[ChartSeries], str, str]  # the curves, the x label and the y label


class BandCharts(Widget):
    """Two charts one above the other, or a line of words (`plain`) when there are none."""

    DEFAULT_CSS = """
    BandCharts { height: auto; width: 1fr; padding: 0 1; }
    """
    CHART_ROWS: ClassVar[int] = 7

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self.plain = ""  # the text of the last render, for tests

    def charts(self) -> list[Chart]:
        """The two charts to draw (none: `words()` instead)."""
        raise NotImplementedError

    def words(self) -> str:
        """What the widget says when it has no charts."""
        return ""

    def get_content_height(self, container: object, viewport: object, width: int) -> int:
        return 2 * (self.CHART_ROWS + 4) + 2 if self.charts() else 1

    def render(self) -> RenderableType:
        charts = self.charts()
        if not charts:
            self.plain = self.words()
            return Text(self.plain)
        width = max(16, self.content_size.width - MARGIN)
        text = Text("\n").join(band_chart(series, width, self.CHART_ROWS, x_label=x_label,
                                          y_label=y_label) for series, x_label, y_label in charts)
        self.plain = text.plain
        return text


class ValueLines(BandCharts):
    """Value curves by state and the policy's numbers (see the module docstring)."""

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self._x = np.zeros(0)
        self._curves: list[tuple[str, np.ndarray]] = []
        self._numbers = np.zeros(0)
        self._labels = ("state", "action")

    def show(self, x: np.ndarray, curves: Sequence[tuple[str, np.ndarray]],
             numbers: np.ndarray, x_label: str, number_label: str) -> None:
        relaid = len(self._x) != len(x)  # the height changes only with the points
        self._x, self._curves, self._numbers = x, list(curves), numbers
        self._labels = (x_label, number_label)
        self.refresh(layout=relaid)

    def charts(self) -> list[Chart]:
        if not len(self._x):
            return []
        x_label, number_label = self._labels
        values = [ChartSeries(name, self._x, np.asarray(v)) for name, v in self._curves]
        finite = np.isfinite(self._numbers)
        policy = [ChartSeries(f"{number_label} (the smallest where several are optimal)",
                              self._x[finite], self._numbers[finite])]
        return [(values, x_label, "value estimates by sweep"),
                (policy, x_label, f"the policy's {number_label}")]
