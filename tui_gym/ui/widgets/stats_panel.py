"""The training stats table: counts, rates, rolling means and the exact yardstick.

`StatsPanel` shows the state of the run (running, paused, finished), the
speed and the engine, then episodes, steps, episodes per second, time,
epsilon and the rolling means of return, length and |TD error|, then the
reference figures the game's profile computes for the current greedy policy
(Blackjack: its exact value beside the optimum and the gap; GridWorld: the
share of (agent, target) pairs solved in the fewest steps). The figures are
shown generically, by name, so a new game needs no change here.
"""

from __future__ import annotations

import textwrap
from collections.abc import Hashable, Mapping
from functools import lru_cache

from rich.segment import Segment
from rich.style import Style
from rich.text import Text

from tui_gym.core.profiles import ReferenceMetrics
from tui_gym.core.training import TrainingSnapshot
from tui_gym.ui.widgets.strip_widget import Line, StripWidget

STATE_STYLES = {
    "running": ("● running", "bold green"),
    "paused": ("‖ paused", "bold yellow"),
    "finished": ("✓ finished", "bold cyan"),
    "idle": ("○ ready", "bold"),
}


def figure_name(key: str) -> str:
    """'optimal_pair_fraction' -> 'optimal pair fraction'."""
    return key.replace("_", " ")


def format_figure(key: str, value: float) -> str:
    """A reference figure as text: shares as percentages, values signed."""
    if key.endswith(("fraction", "rate", "share")):
        return f"{value:.1%}"
    if key == "gap" or key.endswith("_gap"):
        return f"{value:.4f}"
    return f"{value:+.4f}"


def format_duration(seconds: float) -> str:
    seconds = int(seconds)
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def format_rate(rate: float) -> str:
    if rate >= 100:
        return f"{rate:,.0f}"
    return f"{rate:.1f}"


class StatsPanel(StripWidget):
    """A clean two-column table of the run's numbers."""

    # Not scoped: the `Screen.compact ...` rules must match from the screen down.
    SCOPED_CSS = False
    DEFAULT_CSS = """
    StatsPanel {
        width: 1fr;
        max-width: 60;
        height: auto;
        border: round $primary-background-lighten-2;
        border-title-color: $text-muted;
        border-subtitle-color: $text-disabled;
        padding: 0 1;
    }
    Screen.compact StatsPanel {
        max-width: 100%;
        border: none;
        padding: 0;
        min-height: 0;
    }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.border_title = "Training"
        self._rows: list[tuple[str, str, str]] = []  # (name, value, style)
        self._reference: list[tuple[str, str]] = []
        self._engine_reason = ""
        self._shape: tuple = ()
        self._reference_note = ""
        self._state = "idle"
        self._speed = ""
        self._engine = ""
        self._window = 0
        self.plain = ""  # what the panel says, as plain text (tests, screen readers)

    # --- data in -----------------------------------------------------------
    def show_state(self, state: str) -> None:
        """'running', 'paused', 'finished' or 'idle'."""
        if state != self._state:
            self._state = state
            self._changed()

    def show_speed(self, name: str) -> None:
        if name != self._speed:
            self._speed = name
            self._changed()

    def show_snapshot(self, snapshot: TrainingSnapshot) -> None:
        episodes = snapshot.episodes
        seen = episodes > 0
        rows = [
            ("episodes", f"{episodes:,}", "bold"),
            ("steps", f"{snapshot.steps:,}", ""),
            ("eps/s", format_rate(snapshot.episodes_per_second) if seen else "–", ""),
            ("time", format_duration(snapshot.seconds), ""),
            ("epsilon", f"{snapshot.epsilon:.3f}", ""),
            ("return", f"{snapshot.mean_return:+.4f}" if seen else "–", "bold"),
            ("length", f"{snapshot.mean_length:.2f}" if seen else "–", ""),
            ("|TD|", f"{snapshot.mean_abs_td:.4f}" if seen else "–", ""),
        ]
        window = min(snapshot.window, episodes)
        if rows != self._rows or snapshot.engine != self._engine or window != self._window:
            self._rows = rows
            self._engine = snapshot.engine
            self._window = window
            self._changed()

    def show_engine_reason(self, reason: str) -> None:
        """Say which engine trains and why (e.g. a wrapper with no batched form)."""
        if reason != self._engine_reason:
            self._engine_reason = reason
            self._changed()

    def show_reference(self, reference: ReferenceMetrics | None, note: str = "") -> None:
        """The exact comparison with the optimum, or a note on why there is none."""
        figures: Mapping[str, float] = reference.figures if reference else {}
        items = [(figure_name(k), format_figure(k, v)) for k, v in figures.items()]
        if reference is not None and not items:
            items = [("reference", reference.summary)]
        if items != self._reference or note != self._reference_note:
            self._reference = items
            self._reference_note = note
            self._changed()

    # --- drawing -----------------------------------------------------------
    def _changed(self) -> None:
        self.plain = self._plain()
        label, style = STATE_STYLES.get(self._state, (self._state, "bold"))
        title = Text.assemble((label, style))
        if self._speed:
            title.append_text(Text.assemble((" · ", "dim"), (self._speed, "bold")))
        self.border_title = title
        parts = [f"last {self._window:,}"] if self._window else []
        if self._engine:
            parts.append(f"{self._engine} engine")
        self.border_subtitle = " · ".join(parts)
        # A layout pass only when the panel's height may change (new rows or notes).
        shape = (len(self._rows), len(self._reference), bool(self._reference_note),
                 self._engine_reason, self._compact())
        self.redraw(layout=shape != self._shape)
        self._shape = shape

    def _plain(self) -> str:
        label, _ = STATE_STYLES.get(self._state, (self._state, ""))
        lines = [f"{label}  speed {self._speed}  engine {self._engine}"]
        lines += [f"{name} {value}" for name, value, _ in self._rows]
        lines += [f"{name} {value}" for name, value in self._reference]
        if self._reference_note:
            lines.append(self._reference_note)
        if self._engine_reason:
            lines.append(self._engine_reason)
        return "\n".join(lines)

    def picture_key(self) -> Hashable:
        return (self._version, self._compact())

    def get_content_height(self, container: object, viewport: object, width: int) -> int:
        return len(self.picture(width))

    def draw(self, width: int) -> list[Line]:
        label, style = STATE_STYLES.get(self._state, (self._state, "bold"))
        rows: list[list[tuple[str, str]]] = []  # four (text, style) cells a row
        if self._compact():  # no border to carry the state, speed and engine: rows of their own
            rows.append([(label, style), (self._engine, "dim"),
                         ("speed", "dim"), (self._speed or "–", "bold magenta")])
        figures = self._rows
        for i in range(0, len(figures), 2):
            row = []
            for name, value, value_style in figures[i : i + 2]:
                row += [(name, "dim"), (value, value_style)]
            rows.append(row)
        lines = _grid(rows, width)
        if self._reference:
            lines += _grid([[(name, "dim"), (value, "bold")] for name, value in self._reference],
                           width)
        elif self._reference_note:
            lines += _note(self._reference_note, width)
        if self._engine_reason:
            lines += _note(self._engine_reason, width)
        return lines


GAP = 2  # cells between columns


@lru_cache(maxsize=64)
def _style(name: str) -> Style:
    return Style.parse(name) if name else Style()


def _grid(rows: list[list[tuple[str, str]]], width: int) -> list[Line]:
    """Rows of (name, value) pairs: names left-aligned, values right-aligned, the
    value columns sharing the width left over."""
    pairs = max((len(row) // 2 for row in rows), default=0)
    if not pairs:
        return []
    names = [max((len(row[2 * p][0]) for row in rows if len(row) > 2 * p), default=0)
             for p in range(pairs)]
    room = max(0, width - sum(names) - GAP * (2 * pairs - 1))
    values = [room // pairs + (1 if p < room % pairs else 0) for p in range(pairs)]
    lines = []
    for row in rows:
        line: Line = []
        for p in range(len(row) // 2):
            (name, name_style), (value, value_style) = row[2 * p], row[2 * p + 1]
            if p:
                line.append(Segment(" " * GAP))
            line.append(Segment(name, _style(name_style)))
            pad = names[p] + GAP + values[p] - len(name) - len(value)
            line.append(Segment(" " * max(1, pad)))
            line.append(Segment(value, _style(value_style)))
        lines.append(line)
    return lines


def _note(text: str, width: int) -> list[Line]:
    return [[Segment(part, _style("italic dim"))]
            for part in textwrap.wrap(text, max(1, width))]
