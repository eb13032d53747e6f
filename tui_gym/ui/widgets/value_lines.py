"""`ValueLines`: values along one axis of states, drawn as the book draws the gambler's."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from rich.console import RenderableType
from rich.text import Text
from textual.widget import Widget

from tui_gym.terminal_chart import ChartSeries, band_chart

__all__ = ["ValueLines"]

CHART_ROWS = 7
MARGIN = 12  # the y labels and the axis beside the plot


class ValueLines(Widget):
    """Value curves by state and the policy's numbers (see the module docstring)."""

    DEFAULT_CSS = """
    ValueLines { height: auto; width: 1fr; padding: 0 1; }
    """

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self._x = np.zeros(0)
        self._curves: list[tuple[str, np.ndarray]] = []
        self._numbers = np.zeros(0)
        self._labels = ("state", "action")
        self.plain = ""

    def show(self, x: np.ndarray, curves: Sequence[tuple[str, np.ndarray]],
             numbers: np.ndarray, x_label: str, number_label: str) -> None:
        relaid = len(self._x) != len(x)  # the height changes only with the points
        self._x, self._curves, self._numbers = x, list(curves), numbers
        self._labels = (x_label, number_label)
        self.refresh(layout=relaid)

    def get_content_height(self, container: object, viewport: object, width: int) -> int:
        return 2 * (CHART_ROWS + 4) + 2 if len(self._x) else 1

    def render(self) -> RenderableType:
        if not len(self._x):
            self.plain = ""
            return Text("")
        width = max(16, self.content_size.width - MARGIN)
        x_label, number_label = self._labels
        values = [ChartSeries(name, self._x, np.asarray(v)) for name, v in self._curves]
        text = band_chart(values, width, CHART_ROWS, x_label=x_label,
                          y_label="value estimates by sweep")
        text.append("\n")
        finite = np.isfinite(self._numbers)
        policy = [ChartSeries(f"{number_label} (the smallest where several are optimal)",
                              self._x[finite], self._numbers[finite])]
        text.append_text(band_chart(policy, width, CHART_ROWS, x_label=x_label,
                                    y_label=f"the policy's {number_label}"))
        self.plain = text.plain
        return text
