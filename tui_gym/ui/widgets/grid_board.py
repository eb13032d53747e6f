"""`GridBoard`: a square grid with the agent, the target and the agent's trail."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from rich.style import Style
from rich.text import Text
from textual import events
from textual.binding import Binding, BindingType
from textual.geometry import Offset

from tui_gym.ui.widgets.board_drawing import cell_of, stack, step_toward
from tui_gym.ui.widgets.boards import Board, arrow_bindings
from tui_gym.ui.widgets.strip_widget import component_classes

Cell = tuple[int, int]

MOVES: dict[Cell, tuple[str, str]] = {  # (dx, dy) -> (action name, trail arrow)
    (1, 0): ("right", "→"),
    (0, 1): ("up", "↑"),
    (-1, 0): ("left", "←"),
    (0, -1): ("down", "↓"),
}
AGENT, TARGET, HOME = "●", "◎", "◉"  # HOME: the agent stands on the target
WALL = "█"


@dataclass(frozen=True)
class GridLayout:
    """Where the drawn grid sits in the canvas, to map clicks back to cells."""

    n: int
    cell_w: int
    cell_h: int
    lines: bool  # box-drawing lines between cells
    axes: bool  # coordinates to the left and below
    left: int = 0  # canvas column of the grid's left edge (after the y labels)
    top: int = 0  # canvas row of the grid's top edge

    @property
    def label_w(self) -> int:
        return len(str(self.n - 1)) + 1 if self.axes else 0

    @property
    def gap(self) -> int:
        return 1 if self.lines else 0

    @property
    def width(self) -> int:
        return self.label_w + self.n * (self.cell_w + self.gap) + self.gap

    @property
    def height(self) -> int:
        return self.n * (self.cell_h + self.gap) + self.gap + (1 if self.axes else 0)

    def cell_center(self, cell: Cell) -> Offset:
        """The canvas offset of the middle of grid cell (x, y); the inverse of `cell_at`."""
        gap, (x, y) = self.gap, cell
        return Offset(self.left + gap + x * (self.cell_w + gap) + self.cell_w // 2,
                      self.top + gap + (self.n - 1 - y) * (self.cell_h + gap) + self.cell_h // 2)

    def cell_at(self, offset: Offset) -> Cell | None:
        """The grid cell (x, y) under a canvas offset, or None off the grid."""
        gap = self.gap
        col = (offset.x - self.left - gap) // (self.cell_w + gap)
        row = (offset.y - self.top - gap) // (self.cell_h + gap)
        if not (0 <= col < self.n and 0 <= row < self.n):
            return None
        return col, self.n - 1 - row


CELL_SHAPES = (
    (7, 3, True), (5, 2, True), (5, 1, True), (3, 1, True), (3, 1, False), (2, 1, False),
    (1, 1, False),
)


def choose_layout(n: int, width: int, height: int) -> GridLayout:
    """The largest drawing of an n x n grid that fits (the smallest one if none does)."""
    layouts = [GridLayout(n, cell_w, cell_h, lines, axes) for cell_w, cell_h, lines in CELL_SHAPES
               for axes in (True, False) if not (axes and cell_w < len(str(n - 1)))]
    layout = next((layout for layout in layouts if fits(layout, width, height)), layouts[-1])
    return place_layout(layout, width, height)


def fits(layout: GridLayout, width: int, height: int) -> bool:
    """Whether the drawing fits in `width` x `height` cells."""
    return layout.width <= width and layout.height <= height


def place_layout(layout: GridLayout, width: int, height: int) -> GridLayout:
    """The same drawing centred in `width` x `height`."""
    left = max(0, (width - layout.width) // 2) + layout.label_w
    top = max(0, (height - layout.height) // 2)
    return dataclasses.replace(layout, left=left, top=top)


class GridBoard(Board):
    """GridWorld: walk the agent (●) to the target (◎); +y is up."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    GridBoard .grid--line { color: $foreground 30%; }
    GridBoard .grid--empty { color: $foreground 25%; }
    GridBoard .grid--trail { color: $text-primary; }
    GridBoard .grid--agent { background: $primary; color: #ffffff; text-style: bold; }
    GridBoard .grid--target { background: $error 75%; color: #ffffff; text-style: bold; }
    GridBoard .grid--home { background: $success; color: #ffffff; text-style: bold; }
    GridBoard .grid--axis { color: $text-muted; }
    GridBoard .grid--wall { color: $foreground 55%; }
    """

    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    BINDINGS: ClassVar[list[BindingType]] = [
        *arrow_bindings("up", "down", "left", "right", "Move"),
        Binding("r", "new_episode", "Reset", tooltip="Start a new episode"),
    ]

    BUTTONS = (("↺ Reset [dim]r[/]", "new_episode"),)
    BORDER_TITLE = "Grid"
    STYLE = "grid"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.trail: dict[Cell, str] = {}  # cell the agent left -> arrow of that move
        self._grid_agent: Cell | None = None
        self._grid_target: Cell | None = None
        self._grid_size = 0
        self._grid_walls: frozenset[Cell] = frozenset()
        self._grid_fresh = True
        self.layout_drawn: GridLayout | None = None
        self._layout_n = 0  # the grid size the kept cell shape is for (0: choose afresh)
        self._laid_out: tuple[Any, int] | None = None  # (terminal size, board width) last seen

    def on_resize(self, event: events.Resize) -> None:
        # A new terminal size, or a new width (the layout around the board changed, or
        # is settling after a resize): the cell shape is chosen afresh. Lines of text
        # coming and going above or below change only the board's height.
        laid_out = (self.app.size, event.size.width)
        if laid_out != self._laid_out:
            self._laid_out = laid_out
            self._layout_n = 0
            self.redraw()

    # --- what the board says ---------------------------------------------------
    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("↑ ↓ ← →  or  w a s d", "move up, down, left, right (+y is up)"),
            ("r", "reset: a new episode"), ("click a cell", "step one cell towards it"),
        ]

    prompt = "Move with the arrows or WASD, or click a cell; r resets."
    over_hint = "This episode is over: press r (or click Reset) for a new one."

    def button_suggested(self, action: str) -> bool:
        return self.episode_over

    # --- the scene and the trail -----------------------------------------------
    def start_episode(self) -> None:
        """The next scene begins a new episode: forget the trail."""
        self._grid_fresh = True

    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        agent, target = cell_of(scene.get("agent")), cell_of(scene.get("target"))
        size = int(scene.get("size", 0))
        previous = self._grid_agent
        jumped = (
            previous is None
            or agent is None
            or abs(agent[0] - previous[0]) + abs(agent[1] - previous[1]) > 1
        )
        if self._grid_fresh or jumped or target != self._grid_target or size != self._grid_size:
            self.trail = {}
        elif agent != previous and previous is not None and agent is not None:
            move = (agent[0] - previous[0], agent[1] - previous[1])
            self.trail[previous] = MOVES[move][1]
        self._grid_fresh = False
        self._grid_agent, self._grid_target, self._grid_size = agent, target, size
        self._grid_walls = frozenset(c for c in map(cell_of, scene.get("walls", ())) if c)
        super().show_scene(scene, reveal)

    # --- drawing ---------------------------------------------------------------
    def _cell_look(self, cell: Cell, lines: bool) -> tuple[str, Style]:
        """The glyph and style of one cell."""
        if cell == self._grid_agent and cell == self._grid_target:
            return HOME, self._style("home")
        if cell == self._grid_agent:
            return AGENT, self._style("agent")
        if cell == self._grid_target:
            return TARGET, self._style("target")
        if cell in self._grid_walls:
            return WALL, self._style("wall")
        if cell in self.trail:
            return self.trail[cell], self._style("trail")
        return (" " if lines else "·"), self._style("empty")

    def picture(self, width: int, height: int) -> Text:
        n = self._grid_size
        if n <= 0:
            self.layout_drawn = None
            return Text("No grid yet.", self._style("axis"), no_wrap=True, overflow="crop", end="")
        layout = self.layout_drawn = self._steady_layout(n, width, height)
        line, axis = self._style("line"), self._style("axis")
        cw, ch = layout.cell_w, layout.cell_h
        rows: list[Text] = []
        gutter = " " * layout.label_w

        def rule(first: str, middle: str, last: str) -> Text:
            return Text(gutter + first + middle.join("─" * cw for _ in range(n)) + last, line)

        for r in range(n):
            y = n - 1 - r
            if layout.lines:
                rows.append(rule("┌", "┬", "┐") if r == 0 else rule("├", "┼", "┤"))
            for k in range(ch):
                row = Text()
                if layout.axes:
                    label = str(y) if k == ch // 2 else ""
                    row.append(f"{label:>{layout.label_w - 1}} ", axis)
                if layout.lines:
                    row.append("│", line)
                for x in range(n):
                    glyph, style = self._cell_look((x, y), layout.lines)
                    if glyph == WALL:  # a wall fills its cell
                        row.append(WALL * cw, style)
                    else:
                        row.append((glyph if k == ch // 2 else " ").center(cw), style)
                    if layout.lines:
                        row.append("│", line)
                rows.append(row)
        if layout.lines:
            rows.append(rule("└", "┴", "┘"))
        if layout.axes:
            labels = Text(" " * layout.label_w + (" " if layout.lines else ""))
            for x in range(n):
                labels.append(str(x).center(cw) + (" " if layout.lines else ""), axis)
            rows.append(labels)
        return stack(rows, width, height)

    def _steady_layout(self, n: int, width: int, height: int) -> GridLayout:
        """The cell shape kept while it fits (lines around the board come and go), chosen
        afresh for a new grid size or terminal size."""
        kept = self.layout_drawn
        if kept is not None and self._layout_n == n and fits(kept, width, height):
            return place_layout(kept, width, height)
        self._layout_n = n
        return choose_layout(n, width, height)

    def canvas_clicked(self, offset: Offset) -> None:
        """Step one cell towards the clicked cell (the longer way first)."""
        if self.layout_drawn is None or self._grid_agent is None:
            return
        cell, (x, y) = self.layout_drawn.cell_at(offset), self._grid_agent
        if cell is None or cell == (x, y):
            return
        d_y, d_x = step_toward((y, x), (cell[1], cell[0]))  # as (row, col): (y, x)
        self.action_act(MOVES[d_x, d_y][0])
