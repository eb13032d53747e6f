"""The training stats table: counts, rates, rolling means and the exact yardstick."""

from __future__ import annotations

import textwrap
from collections.abc import Mapping
from functools import lru_cache

from rich.segment import Segment
from rich.style import Style
from rich.text import Text

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.games.base import ReferenceMetrics
from tui_gym.ui.widgets.numbers import Forms, compact_count, count_forms, fit, number_forms
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, panel_css

STATE_STYLES = {
    "running": ("● running", "bold green"), "paused": ("‖ paused", "bold yellow"),
    "finished": ("✓ finished", "bold cyan"), "idle": ("○ ready", "bold"),
}


def run_state(running: bool, episodes: int, steps: int, budget: int) -> str:
    """'running', 'finished' (a budget of `budget` episodes was used up), 'paused'
    (training has begun: an episode, or a step of one) or 'idle' (nothing yet)."""
    if running:
        return "running"
    if episodes > 0 and episodes >= budget:
        return "finished"
    if episodes > 0 or steps > 0:
        return "paused"
    return "idle"


def figure_forms(key: str, value: float) -> Forms:
    """A reference figure as text (shares as percentages, values signed), then shorter
    forms of the same number (for narrow screens)."""
    if key.endswith(("fraction", "rate", "share")):
        return (f"{value:.1%}",)
    return number_forms(value, ".4f" if key == "gap" or key.endswith("_gap") else "+.4f")


def format_duration(seconds: float) -> str:
    seconds = int(seconds)
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


NO_DATA = "–"


class StatsPanel(StripWidget):
    """A clean two-column table of the run's numbers."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = panel_css("StatsPanel") + """
    StatsPanel { width: 1fr; max-width: 60; }
    Screen.compact StatsPanel { max-width: 100%; min-height: 0; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.border_title = "Training"
        self._rows: list[tuple[str, Forms, str]] = []  # (name, value's forms, style)
        self._reference: list[tuple[str, Forms]] = []
        self._scope_note = ""
        self._shape: tuple = ()
        self._reference_note = ""
        self._state = "idle"
        self._speed = ""
        self._engine = ""
        self._window = 0
        self._border: tuple[str, str, str] | None = None  # (state, speed, subtitle) shown
        self.plain = ""  # what the panel says, as plain text (tests, screen readers)

    # --- data in -----------------------------------------------------------
    def show_state(self, state: str) -> None:
        """'running', 'paused', 'finished' or 'idle'."""
        self._show(_state=state)

    def show_speed(self, name: str) -> None:
        self._show(_speed=name)

    def show_snapshot(self, snapshot: TrainingSnapshot) -> None:
        recorded = snapshot.recorded > 0  # episodes in the rolling statistics
        rate = snapshot.episodes_per_second
        none: Forms = (NO_DATA,)
        rows: list[tuple[str, Forms, str]] = [
            ("episodes", count_forms(snapshot.episodes), "bold"),
            ("steps", count_forms(snapshot.steps), ""),
            ("eps/s", (f"{rate:,.0f}" if rate >= 100 else f"{rate:.1f}", compact_count(rate))
             if rate > 0 else none, ""),
            ("time", (format_duration(snapshot.seconds),) if snapshot.seconds > 0 else none, ""),
            ("epsilon", (f"{snapshot.epsilon:.3f}",), ""),
            ("return", number_forms(snapshot.mean_return, "+.4f") if recorded else none, "bold"),
            ("length", number_forms(snapshot.mean_length, ".2f") if recorded else none, ""),
            ("|TD|", number_forms(snapshot.mean_abs_td, ".4f") if recorded else none, ""),
        ]
        self._show(_rows=rows, _engine=snapshot.engine,
                   _window=min(snapshot.window, snapshot.recorded))

    def show_reference(self, reference: ReferenceMetrics | None, note: str = "") -> None:
        """The exact comparison with the optimum (and a word on what it takes into
        account), or a note on why there is none."""
        figures: Mapping[str, float] = reference.figures if reference else {}
        items = [(k.replace("_", " "), figure_forms(k, v)) for k, v in figures.items()]
        if reference is not None and not items:
            items = [("reference", (reference.summary,))]
        scope = reference.scope.note if reference is not None else ""
        self._show(_reference=items, _reference_note=note, _scope_note=scope)

    # --- drawing -----------------------------------------------------------
    def _show(self, **values: object) -> None:
        """Take these attributes' new values; the panel changes when one of them does."""
        if any(getattr(self, name) != value for name, value in values.items()):
            for name, value in values.items():
                setattr(self, name, value)
            self._changed()

    def _changed(self) -> None:
        self.plain = self._plain()
        parts = [f"last {self._window:,}"] if self._window else []
        if self._engine:
            parts.append(f"{self._engine} engine")
        border = (self._state, self._speed, " · ".join(parts))
        if border != self._border:  # setting a border's words repaints the whole panel
            self._border = border
            label, style = STATE_STYLES.get(self._state, (self._state, "bold"))
            title = Text.assemble((label, style))
            if self._speed:
                title.append_text(Text.assemble((" · ", "dim"), (self._speed, "bold")))
            self.border_title = title
            self.border_subtitle = border[2]
        # A layout pass only when the panel's height may change (new rows or notes).
        shape = (len(self._rows), len(self._reference), bool(self._reference_note),
                 self._scope_note, self._compact())
        self.redraw(layout=shape != self._shape)
        self._shape = shape

    def _plain(self) -> str:
        label, _ = STATE_STYLES.get(self._state, (self._state, ""))
        lines = [f"{label}  speed {self._speed}  engine {self._engine}"]
        lines += [f"{name} {forms[0]}" for name, forms, _ in self._rows]
        lines += [f"{name} {forms[0]}" for name, forms in self._reference]
        if self._scope_note:
            lines.append(self._scope_note)
        if self._reference_note:
            lines.append(self._reference_note)
        return "\n".join(lines)

    def draw(self, width: int) -> list[Line]:
        label, style = STATE_STYLES.get(self._state, (self._state, "bold"))
        lines: list[Line] = []
        if self._compact():  # no border to carry the state, speed and engine: rows of their own
            lines += _grid([[(label, style), ((self._engine,), "dim"),
                             ("speed", "dim"), ((self._speed or NO_DATA,), "bold magenta")]],
                           width)
        lines += _grid([[(name, "dim"), (forms, value_style)]
                        for name, forms, value_style in self._rows], width, per_row=2)
        if self._reference:
            lines += _grid([[(name, "dim"), (forms, "bold")] for name, forms in self._reference],
                           width)
        if self._reference and self._scope_note:
            lines += _note(self._scope_note, width)
        if self._reference_note:
            lines += _note(self._reference_note, width)
        return lines


GAP = 2  # cells between columns
Cell = tuple[str | Forms, str]  # a name (one text) or a value (its forms), and its style


@lru_cache(maxsize=64)
def _style(name: str) -> Style:
    return Style.parse(name) if name else Style()


def _grid(rows: list[list[Cell]], width: int, per_row: int = 0) -> list[Line]:
    """Rows of (name, value) pairs (`per_row` > 0: regrouped that many to a row, fewer when
    they do not fit), names left-aligned, values right-aligned in shorter forms, never cut."""
    paired = [list(zip(row[::2], row[1::2], strict=True)) for row in rows]
    pairs = [pair for row in paired for pair in row]
    if not pairs:
        return []
    if per_row > 1:
        lines = _lay_out([pairs[i : i + per_row] for i in range(0, len(pairs), per_row)], width,
                         fit_only=True)
        return lines if lines is not None else _lay_out([[pair] for pair in pairs], width) or []
    return _lay_out(paired, width) or []


def _as_forms(value: str | Forms) -> Forms:
    return (value,) if isinstance(value, str) else value


def _lay_out(rows: list[list], width: int, fit_only: bool = False) -> list[Line] | None:
    """The lines of rows of ((name, style), (value forms, style)) pairs, or None when
    `fit_only` and they do not fit in `width`."""
    columns = max(len(row) for row in rows)
    names = [max((len(row[p][0][0]) for row in rows if len(row) > p), default=0)
             for p in range(columns)]
    forms = [[_as_forms(row[p][1][0]) for row in rows if len(row) > p] for p in range(columns)]
    gap = GAP
    room = width - sum(names) - columns - gap * (columns - 1)  # a space before each value
    widths = [max(len(f[0]) for f in column) for column in forms]
    while sum(widths) > room:  # the widest column takes the next shorter forms
        p = max(range(columns), key=widths.__getitem__)
        narrower = max(len(fit(f, widths[p] - 1)) for f in forms[p])
        if narrower >= widths[p]:
            break
        widths[p] = narrower
    if sum(widths) > room:
        if fit_only:
            return None
        gap = 1  # the last resort: closer columns
        room = width - sum(names) - columns - gap * (columns - 1)
    spare = max(0, room - sum(widths))  # shared out, so the values end where the width does
    values = [widths[p] + spare // columns + (1 if p < spare % columns else 0)
              for p in range(columns)]
    lines = []
    for row in rows:
        line: Line = []
        for p, ((name, name_style), (value, value_style)) in enumerate(row):
            text = fit(_as_forms(value), widths[p])
            if p:
                line.append(Segment(" " * gap))
            line.append(Segment(name, _style(name_style)))
            pad = names[p] + 1 + values[p] - len(name) - len(text)
            line.append(Segment(" " * max(1, pad)))
            line.append(Segment(text, _style(value_style)))
        lines.append(line)
    return lines


def _note(text: str, width: int) -> list[Line]:
    return [[Segment(part, _style("italic dim"))] for part in textwrap.wrap(text, max(1, width))]
