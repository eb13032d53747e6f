"""Learning curves: four labelled text sparklines of a training run.

`TrainingCharts` shows the rolling mean return, episode length, mean |TD
error| and epsilon as Textual `Sparkline`s over the whole run (the trainer's
bounded `series`), each with its name, its current value and the range the
curve spans. `update_from(snapshot)` touches a sparkline only when its data
changed, so a paused run costs nothing to redraw.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.widgets import Label, Sparkline

from tui_gym.core.training import TrainingSnapshot


def _mean(values: Sequence[float]) -> float:
    return sum(values) / len(values) if values else 0.0


@dataclass(frozen=True)
class Curve:
    """One chart: which series, its name, and how its numbers read."""

    key: str  # key in TrainingSnapshot.series
    name: str
    current: Callable[[TrainingSnapshot], float]
    fmt: str


CURVES: tuple[Curve, ...] = (
    Curve("return", "mean return", lambda s: s.mean_return, "{:+.3f}"),
    Curve("length", "ep. length", lambda s: s.mean_length, "{:.2f}"),
    Curve("td_error", "mean |TD|", lambda s: s.mean_abs_td, "{:.4f}"),
    Curve("epsilon", "epsilon", lambda s: s.epsilon, "{:.3f}"),
)


class TrainingCharts(Vertical):
    """Four sparklines with names, current values and ranges."""

    # Not scoped: the `Screen.compact ...` rules must match from the screen down.
    SCOPED_CSS = False
    DEFAULT_CSS = """
    TrainingCharts {
        height: auto;
        border: round $primary-background-lighten-2;
        border-title-color: $text-muted;
        padding: 0 1;
    }
    TrainingCharts > .chart {
        height: 2;
    }
    TrainingCharts .chart-name {
        width: 12;
        color: $text-muted;
    }
    TrainingCharts .chart-value {
        width: 9;
        text-align: right;
        text-style: bold;
    }
    TrainingCharts .chart-range {
        width: 13;
        height: 2;
    }
    TrainingCharts .chart-range Label {
        width: 100%;
        color: $text-disabled;
        text-align: right;
    }
    TrainingCharts Sparkline {
        width: 1fr;
        height: 2;
        margin: 0 1;
    }
    TrainingCharts #chart-return Sparkline > .sparkline--max-color { color: $success; }
    TrainingCharts #chart-return Sparkline > .sparkline--min-color { color: $error 70%; }
    TrainingCharts #chart-length Sparkline > .sparkline--max-color { color: $accent; }
    TrainingCharts #chart-length Sparkline > .sparkline--min-color { color: $accent 40%; }
    TrainingCharts #chart-td_error Sparkline > .sparkline--max-color { color: $error; }
    TrainingCharts #chart-td_error Sparkline > .sparkline--min-color { color: $error 40%; }
    TrainingCharts #chart-epsilon Sparkline > .sparkline--max-color { color: $primary; }
    TrainingCharts #chart-epsilon Sparkline > .sparkline--min-color { color: $primary 40%; }

    Screen.compact TrainingCharts {
        border: none;
        padding: 0;
    }
    Screen.compact TrainingCharts > .chart,
    Screen.compact TrainingCharts Sparkline {
        height: 1;
    }
    Screen.compact TrainingCharts .chart-range {
        display: none;
    }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self._shown: dict[str, tuple[float, ...]] = {}
        self._values: dict[str, str] = {}
        self._sparks: dict[str, Sparkline] = {}
        self._labels: dict[str, tuple[Label, Label, Label]] = {}
        self.border_title = "Learning curves"

    def compose(self) -> ComposeResult:
        for curve in CURVES:
            key = curve.key
            self._sparks[key] = Sparkline([], summary_function=_mean, id=f"spark-{key}")
            self._labels[key] = (
                Label("–", classes="chart-value", id=f"value-{key}"),
                Label("", id=f"high-{key}"),
                Label("", id=f"low-{key}"),
            )
            value, high, low = self._labels[key]
            with Horizontal(classes="chart", id=f"chart-{key}"):
                yield Label(curve.name, classes="chart-name")
                yield value
                yield self._sparks[key]
                with Vertical(classes="chart-range"):
                    yield high
                    yield low

    def sparkline(self, key: str) -> Sparkline:
        """The sparkline of one series ("return", "length", "td_error", "epsilon")."""
        return self._sparks[key]

    def value_text(self, key: str) -> str:
        """The current value shown beside a sparkline."""
        return self._values.get(key, "")

    def clear(self) -> None:
        """Forget every curve (after an agent reset)."""
        self._shown.clear()
        self._values.clear()
        self.border_title = "Learning curves"
        for curve in CURVES:
            self._sparks[curve.key].data = []
            value, high, low = self._labels[curve.key]
            value.update("–")
            high.update("")
            low.update("")

    def update_from(self, snapshot: TrainingSnapshot) -> None:
        """Show a snapshot's curves, redrawing only the ones that changed."""
        window = min(snapshot.window, max(1, snapshot.episodes))
        title = (
            f"Learning curves · rolling mean of {window:,}"
            if snapshot.episodes
            else "Learning curves"
        )
        if title != self.border_title:
            self.border_title = title
        for curve in CURVES:
            key = curve.key
            value, high, low = self._labels[key]
            data = tuple(snapshot.series.get(key, ()))
            if self._shown.get(key) != data:
                self._shown[key] = data
                self._sparks[key].data = data
                # Fixed-size labels: no layout pass needed (it would cost a whole frame).
                high.update(f"max {curve.fmt.format(max(data))}" if data else "", layout=False)
                low.update(f"min {curve.fmt.format(min(data))}" if data else "", layout=False)
            text = curve.fmt.format(curve.current(snapshot)) if snapshot.episodes else "–"
            if self._values.get(key) != text:
                self._values[key] = text
                value.update(text, layout=False)


__all__ = ["CURVES", "Curve", "TrainingCharts"]
