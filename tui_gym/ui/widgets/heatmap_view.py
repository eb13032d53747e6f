"""`HeatmapView`: Q-table heatmap panels on one colour scale, with a legend and a focus
cell that the arrow keys or a click move (posting `FocusChanged`)."""

from __future__ import annotations

import textwrap
from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, ClassVar

import numpy as np
from rich.segment import Segment
from rich.style import Style
from rich.text import Text
from textual import events
from textual.binding import Binding, BindingType
from textual.geometry import Size
from textual.message import Message
from textual.reactive import reactive

from tui_gym.core.heatmap import Heatmap
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, line_text, segments_of

RGB = tuple[int, int, int]

# Sequential scale (viridis), for values of one sign.
SEQUENTIAL: tuple[RGB, ...] = (
    (68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37),
)
# Diverging scale with a dark middle: losses red, zero dim, gains green.
DIVERGING: tuple[RGB, ...] = (
    (215, 48, 39), (160, 70, 60), (58, 58, 66), (50, 140, 90), (90, 210, 120),
)
MAX_CELL_WIDTH = 6
COLOUR_STEPS = 128  # cell colours are drawn from this many steps along the scale
PANEL_GAP = 4
LEGEND_WIDTH = 24


def _interpolate(stops: Sequence[RGB], t: float) -> RGB:
    """The colour at `t` in [0, 1] along evenly spaced stops."""
    t = min(1.0, max(0.0, t))
    pos = t * (len(stops) - 1)
    i = min(int(pos), len(stops) - 2)
    frac = pos - i
    a, b = stops[i], stops[i + 1]
    return tuple(round(a[k] + (b[k] - a[k]) * frac) for k in range(3))  # type: ignore[return-value]


def _hex(rgb: RGB) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


@dataclass(frozen=True)
class ColourScale:
    """Maps values onto colours: diverging around 0 when the range crosses it."""

    low: float
    high: float

    @classmethod
    def over(cls, panels: Sequence[Heatmap]) -> ColourScale:
        ranges = [panel.value_range() for panel in panels if np.isfinite(panel.values).any()]
        if not ranges:
            return cls(0.0, 0.0)
        return cls(min(low for low, _ in ranges), max(high for _, high in ranges))

    @property
    def diverging(self) -> bool:
        return self.low < 0.0 < self.high

    @property
    def bounds(self) -> tuple[float, float]:
        """The values at the two ends of the scale."""
        if self.diverging:
            m = max(-self.low, self.high)
            return -m, m
        return self.low, self.high

    def steps(self, values: np.ndarray) -> np.ndarray:
        """Each value's step on the scale, 0 .. COLOUR_STEPS - 1 (-1 where not finite)."""
        lo, hi = self.bounds
        finite = np.isfinite(values)
        if hi <= lo:
            position = np.full(values.shape, 0.5)
        else:
            with np.errstate(invalid="ignore"):
                position = np.clip((values - lo) / (hi - lo), 0.0, 1.0)
        steps = np.rint(np.where(finite, position, 0.0) * (COLOUR_STEPS - 1)).astype(int)
        return np.where(finite, steps, -1)


@dataclass(frozen=True)
class _Placement:
    """Where one panel's cells sit in the rendered text."""

    index: int
    x: int  # column of the first cell
    y: int  # line of the first row of cells
    rows: int
    cols: int


@dataclass(frozen=True)
class _Layout:
    side_by_side: bool
    cell_width: int
    cell_height: int
    row_label_width: int
    panel_width: int


class HeatmapView(StripWidget, can_focus=True):
    """Heatmap panels of a Q-table, with a movable focus cell for games that have one."""

    DEFAULT_CSS = """
    HeatmapView {
        width: 1fr;
        height: auto;
        text-wrap: nowrap;
        text-overflow: clip;
        padding: 0 1;
        &:focus {
            background-tint: $foreground 3%;
        }
        &.-empty {
            color: $text-muted;
            text-style: italic;
            text-wrap: wrap;
            content-align: center middle;
            height: 5;
        }
    }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("up,k", "move(-1, 0)", "Target up", show=False),
        Binding("down,j", "move(1, 0)", "Target down", show=False),
        Binding("left,h", "move(0, -1)", "Target left", show=False),
        Binding("right,l", "move(0, 1)", "Target right", show=False),
    ]

    @dataclass
    class FocusChanged(Message):
        """The focus cell was moved (keys) or picked (click)."""

        view: HeatmapView
        cell: tuple[int, int]  # (row, col) in the first panel

        @property
        def control(self) -> HeatmapView:
            return self.view

    # (row, col) of the focus cell (None: the game has none); (panel, row, col) of the state
    # the step-by-step panel explains, or None.
    focus_cell: reactive[tuple[int, int] | None] = reactive(None, init=False)
    step_cell: reactive[tuple[int, int, int] | None] = reactive(None, init=False)

    def __init__(self, panels: Sequence[Heatmap] = (), **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.panels: tuple[Heatmap, ...] = tuple(panels)
        self._message = ""
        self._placements: list[_Placement] = []
        self._cell_geometry = (3, 1)
        self.plain = ""  # the text of the last render, for tests and screenshots

    # --- data in -----------------------------------------------------------
    def show(self, panels: Sequence[Heatmap]) -> None:
        """Draw these panels (replacing any message)."""
        old = self.panels
        self.panels = tuple(panels)
        self._message = ""
        self.remove_class("-empty")
        same_shape = len(old) == len(self.panels) and all(
            a.shape == b.shape and len(a.legend) == len(b.legend)
            for a, b in zip(old, self.panels, strict=True)
        )
        self.redraw(layout=not same_shape)

    def show_message(self, text: str) -> None:
        """Show a line of text instead of panels (e.g. why there is no per-state view)."""
        self.panels = ()
        self._message = text
        self.add_class("-empty")
        self.redraw(layout=True)

    def watch_focus_cell(self, old: object, new: object) -> None:
        if (old is None) != (new is None):  # the move keys come or go
            self.refresh_bindings()

    # --- keys and clicks ---------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "move":
            return self.focus_cell is not None and bool(self.panels)
        return True

    def action_move(self, d_row: int, d_col: int) -> None:
        assert self.focus_cell is not None  # see check_action
        rows, cols = self.panels[0].shape
        row, col = self.focus_cell
        self._focus_on((min(rows - 1, max(0, row + d_row)), min(cols - 1, max(0, col + d_col))))

    def _focus_on(self, cell: tuple[int, int]) -> None:
        if cell != self.focus_cell:
            self.focus_cell = cell
            self.post_message(self.FocusChanged(self, cell))

    def cell_at(self, x: int, y: int) -> tuple[int, int, int] | None:
        """(panel, row, col) under content offset (x, y), or None."""
        cell_w, cell_h = self._cell_geometry
        for place in self._placements:
            dx, dy = x - place.x, y - place.y
            if 0 <= dx < place.cols * cell_w and 0 <= dy < place.rows * cell_h:
                return place.index, dy // cell_h, dx // cell_w
        return None

    def clicked_cell(self, event: events.Click) -> tuple[int, int] | None:
        """The first panel's (row, col) a click hit; the view then takes the click and the focus."""
        offset = event.get_content_offset(self)
        hit = None if offset is None or not self.panels else self.cell_at(offset.x, offset.y)
        if hit is None or hit[0] != 0:
            return None
        event.stop()
        self.focus()
        return hit[1], hit[2]

    def on_click(self, event: events.Click) -> None:
        cell = None if self.focus_cell is None else self.clicked_cell(event)
        if cell is not None:
            self._focus_on(cell)

    # --- layout ------------------------------------------------------------
    def _layout(self, width: int) -> _Layout:
        panels = self.panels
        rows = max(p.shape[0] for p in panels)
        cols = max(p.shape[1] for p in panels)
        row_label_width = max((len(label) for p in panels for label in p.row_labels), default=0)
        longest = max(
            (len(text) for p in panels for line in p.labels for text in line), default=1
        )
        min_cell = max(3, longest + 2, *(len(c) + 1 for p in panels for c in p.col_labels))
        fixed = row_label_width + 1
        n = len(panels)
        side = (width - n * fixed - PANEL_GAP * (n - 1)) // max(1, n * cols)
        side_by_side = n == 1 or side >= min_cell
        room = side if side_by_side else (width - fixed) // max(1, cols)
        cell_width = max(min_cell, min(MAX_CELL_WIDTH, room))
        # Tall cells look square when there is room: few rows, wide cells, not compact.
        cell_height = 2 if (rows <= 8 and cell_width >= 5 and not self._compact()) else 1
        panel_width = fixed + cols * cell_width
        return _Layout(side_by_side, cell_width, cell_height, row_label_width, panel_width)

    def get_content_width(self, container: Size, viewport: Size) -> int:
        if not self.panels:
            return len(self._message)
        layout = self._layout(container.width)
        n = len(self.panels) if layout.side_by_side else 1
        return n * layout.panel_width + PANEL_GAP * (n - 1)

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        if not self.panels:
            return max(1, len(self._message) // max(1, width) + 1)
        return len(self.picture(width))

    # --- drawing -----------------------------------------------------------
    def picture_key(self) -> Hashable:
        height = 0 if self.panels else self.content_size.height  # a message is centred
        return (self._version, self.focus_cell, self.step_cell, self.has_focus, self._compact(),
                height)

    def draw(self, width: int) -> list[Line]:
        if not self.panels:
            self.plain = self._message
            self._placements = []
            console = self.app.console
            wrapped = Text(self._message).wrap(console, max(1, width), justify="center")
            top = max(0, (self.content_size.height - len(wrapped)) // 2)
            return [[] for _ in range(top)] + [segments_of(t, console)[0] for t in wrapped]
        layout = self._layout(width)
        scale = ColourScale.over(self.panels)
        several = layout.side_by_side and len(self.panels) > 1
        title_width = layout.panel_width if several else width
        blocks = [self._panel_lines(i, p, layout, scale, title_width)
                  for i, p in enumerate(self.panels)]
        lines: list[_Line] = []
        placements: list[_Placement] = []
        if layout.side_by_side:
            height = max(len(b) for b in blocks)
            for y in range(height):
                line = _Line()
                for i, block in enumerate(blocks):
                    if i:
                        line.add(" " * PANEL_GAP)
                    part = block[y] if y < len(block) else _Line()
                    for segment in part:
                        line.add(segment.text, segment.style)
                    line.add(" " * max(0, layout.panel_width - part.width))
                lines.append(line)
            for i, panel in enumerate(self.panels):
                x = i * (layout.panel_width + PANEL_GAP) + layout.row_label_width + 1
                placements.append(_Placement(i, x, 2, *panel.shape))
        else:
            for i, (panel, block) in enumerate(zip(self.panels, blocks, strict=True)):
                if i:
                    lines.append(_Line())
                x, y = layout.row_label_width + 1, len(lines) + 2  # below the title and labels
                placements.append(_Placement(i, x, y, *panel.shape))
                lines.extend(block)
        lines.append(self._scale_line(scale, layout, width))
        indent = layout.row_label_width + 1
        for legend in dict.fromkeys(panel.legend for panel in self.panels if panel.legend):
            for text in textwrap.wrap(legend, max(12, width - indent)):  # each legend once
                lines.append(_Line().add(" " * indent + text, DIM))
        self._placements = placements
        self._cell_geometry = (layout.cell_width, layout.cell_height)
        cropped = [Segment.adjust_line_length(line, width, pad=False) for line in lines]
        self.plain = "\n".join(line_text(line).rstrip() for line in cropped)
        return cropped

    def _panel_lines(
        self, index: int, panel: Heatmap, layout: _Layout, scale: ColourScale, title_width: int
    ) -> list[_Line]:
        cw, ch, rlw = layout.cell_width, layout.cell_height, layout.row_label_width
        rows, cols = panel.shape
        grid_width = cols * cw
        title = panel.title
        if len(title) <= grid_width:
            title = " " * (rlw + 1) + title.center(grid_width).rstrip()
        lines = [_Line().add(title[:title_width], BOLD)]
        header = _Line().add(" " * (rlw + 1))
        for label in panel.col_labels:
            header.add(label.center(cw), DIM)
        lines.append(header)
        focus = self.focus_cell if index == 0 else None
        step = self.step_cell[1:] if self.step_cell and self.step_cell[0] == index else None
        has_focus = self.has_focus
        steps = scale.steps(np.asarray(panel.values, dtype=float)).tolist()
        marked_cells = panel.marked.tolist()
        for r in range(rows):
            for sub in range(ch):
                row_label = panel.row_labels[r] if sub == 0 else ""
                line = _Line().add(row_label.rjust(rlw) + " ", DIM)
                for c in range(cols):
                    label = panel.labels[r][c] if sub == 0 else ""
                    marked = bool(marked_cells[r][c]) and sub == 0
                    pad = (cw - len(label)) // 2
                    body = (" " * pad + label + ("*" if marked else "")).ljust(cw)[:cw]
                    if step == (r, c):  # the state of the step being explained
                        style = STEP_CELL
                        body = ("[" + body[1:-1] + "]") if cw >= 3 else body
                    elif focus == (r, c):  # bright while the keys move it, quiet otherwise
                        style = FOCUS_ACTIVE if has_focus else FOCUS_QUIET
                    else:
                        style = _cell_style(scale.diverging, steps[r][c], marked)
                    line.add(body, style)
                lines.append(line)
        return lines

    def _scale_line(self, scale: ColourScale, layout: _Layout, width: int) -> _Line:
        lo, hi = scale.bounds
        indent = layout.row_label_width + 1
        bar = max(4, min(LEGEND_WIDTH, width - indent - 12))
        line = _Line().add(" " * indent)
        line.add(f"{lo:+.2f} ", DIM)
        for i in range(bar):
            rgb = _interpolate(DIVERGING if scale.diverging else SEQUENTIAL, (i + 0.5) / bar)
            line.add(" ", Style(bgcolor=_hex(rgb)))
        line.add(f" {hi:+.2f}", DIM)
        return line


DIM = Style(dim=True)
BOLD = Style(bold=True)
FOCUS_ACTIVE = Style(bold=True, color="#000000", bgcolor="#f5f5f5")
FOCUS_QUIET = Style(bold=True, color="#f5f5f5", bgcolor="#5a5a5a")
STEP_CELL = Style(bold=True, color="#000000", bgcolor="#ffd75f")
BLANK_CELL = Style(color="#808080")


@lru_cache(maxsize=4 * COLOUR_STEPS + 1)
def _cell_style(diverging: bool, step: int, marked: bool) -> Style:
    """A cell's style by its step on the scale (-1: no value); kept, as cells share them."""
    if step < 0:
        return BLANK_CELL
    rgb = _interpolate(DIVERGING if diverging else SEQUENTIAL, step / (COLOUR_STEPS - 1))
    r, g, b = rgb  # the ink black or white, whichever reads better on the colour
    ink = "#101010" if (0.299 * r + 0.587 * g + 0.114 * b) / 255 > 0.55 else "#f0f0f0"
    return Style(bgcolor=_hex(rgb), color=ink, bold=marked, underline=marked)


class _Line(list):
    """Segments of one line, with their width (every character is one cell wide)."""

    width = 0

    def add(self, text: str, style: Style | None = None) -> _Line:
        if text:
            self.append(Segment(text, style))
            self.width += len(text)
        return self
