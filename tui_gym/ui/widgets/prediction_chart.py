"""`PredictionChart`: a prediction learner's RMS error over episodes, and V state by state."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tui_gym.terminal_chart import ChartSeries
from tui_gym.ui.widgets.value_lines import BandCharts, Chart

if TYPE_CHECKING:
    from tui_gym.session.session import PredictionFigures

__all__ = ["MAX_POINTS", "PredictionChart"]

MAX_POINTS = 512


class PredictionChart(BandCharts):
    """The RMS curve and V against V^π (see the module docstring)."""

    CHART_ROWS = 6

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self._episodes: list[float] = []
        self._rms: list[float] = []
        self._figures: PredictionFigures | None = None
        self._reason = ""

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

    def words(self) -> str:
        return f"RMS error of V: n/a ({self._reason})" if self._reason else ""

    def charts(self) -> list[Chart]:
        figures = self._figures
        if figures is None:
            return []
        curve = ChartSeries(f"RMS error of V: {figures.rms:.4f}", np.array(self._episodes),
                            np.array(self._rms))
        states = np.array(figures.states, dtype=np.float64)
        return [([curve], "episodes", "RMS error of V against the exact V^π"),
                ([ChartSeries("estimate V", states, np.array(figures.estimate)),
                  ChartSeries("true V^π", states, np.array(figures.truth))],
                 "state", "V by state")]
