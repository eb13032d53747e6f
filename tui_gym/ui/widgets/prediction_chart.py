"""`PredictionChart`: a prediction learner's RMS error over episodes, and V state by state."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from rich.console import RenderableType
from rich.text import Text
from textual.widget import Widget

from tui_gym.terminal_chart import ChartSeries, band_chart

if TYPE_CHECKING:
    from tui_gym.session.prediction import PredictionFigures

__all__ = ["MAX_POINTS", "PredictionChart"]

CHART_ROWS = 6
MARGIN = 12  # the y labels and the axis beside the plot
MAX_POINTS = 512


class PredictionChart(Widget):
    """The RMS curve and V against V^π (see the module docstring)."""

    DEFAULT_CSS = """
    PredictionChart { height: auto; width: 1fr; padding: 0 1; }
    """

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self._episodes: list[float] = []
        self._rms: list[float] = []
        self._figures: PredictionFigures | None = None
        self._reason = ""
        self.plain = ""

    def clear(self) -> None:
        self._episodes, self._rms, self._figures, self._reason = [], [], None, ""
        self.refresh(layout=True)

    def show(self, episodes: int, figures: PredictionFigures) -> None:
        if self._episodes and episodes < self._episodes[-1]:
            self._episodes, self._rms = [], []
        if self._episodes and episodes == self._episodes[-1]:
            self._rms[-1] = figures.rms
        else:
            self._episodes.append(float(episodes))
            self._rms.append(figures.rms)
        if len(self._episodes) > MAX_POINTS:
            self._episodes, self._rms = self._episodes[::2], self._rms[::2]
        relaid = self._figures is None or self._reason != ""
        self._figures, self._reason = figures, ""
        self.refresh(layout=relaid)

    def show_reason(self, reason: str) -> None:
        relaid = self._figures is not None
        self._figures, self._reason = None, reason
        self.refresh(layout=relaid)

    @property
    def rms_points(self) -> list[tuple[float, float]]:
        """(episodes, RMS error) of each point of the curve."""
        return list(zip(self._episodes, self._rms, strict=True))

    def get_content_height(self, container: object, viewport: object, width: int) -> int:
        return 2 * (CHART_ROWS + 4) + 2 if self._figures is not None else 1

    def render(self) -> RenderableType:
        figures = self._figures
        if figures is None:
            self.plain = f"RMS error of V: n/a ({self._reason})" if self._reason else ""
            return Text(self.plain)
        width = max(16, self.content_size.width - MARGIN)
        curve = ChartSeries(f"RMS error of V: {figures.rms:.4f}", np.array(self._episodes),
                            np.array(self._rms))
        text = band_chart([curve], width, CHART_ROWS, x_label="episodes",
                          y_label="RMS error of V against the exact V^π")
        text.append("\n")
        states = np.array(figures.states, dtype=np.float64)
        text.append_text(band_chart(
            [ChartSeries("estimate V", states, np.array(figures.estimate)),
             ChartSeries("true V^π", states, np.array(figures.truth))],
            width, CHART_ROWS, x_label="state", y_label="V by state"))
        self.plain = text.plain
        return text
