"""`GridBoard`: a square grid with the agent, the target and the agent's trail."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from rich.style import Style
from rich.text import Text
from textual import events
from textual.binding import Binding, BindingType
from textual.geometry import Offset

from tui_gym.ui.widgets.board_drawing import CharGrid, MapBoard, MapShape, cell_of, shape_fits
from tui_gym.ui.widgets.boards import arrow_bindings
from tui_gym.ui.widgets.strip_widget import component_classes

Cell = tuple[int, int]  # (x, y), +y up

MOVES: dict[Cell, tuple[str, str]] = {  # (dx, dy) -> (action name, trail arrow)
    (1, 0): ("right", "→"),
    (0, 1): ("up", "↑"),
    (-1, 0): ("left", "←"),
    (0, -1): ("down", "↓"),
}
ROW_MOVES = {(-dy, dx): name for (dx, dy), (name, _) in MOVES.items()}  # by (d_row, d_col)
AGENT, TARGET, HOME = "●", "◎", "◉"  # HOME: the agent stands on the target
WALL = "█"

# (cell_w, cell_h, box-drawing lines between cells), largest first
CELL_SHAPES = (
    (7, 3, True), (5, 2, True), (5, 1, True), (3, 1, True), (3, 1, False), (2, 1, False),
    (1, 1, False),
)


def choose_shape(rows: int, cols: int, width: int, height: int) -> MapShape:
    """The largest drawing of a rows x cols grid that fits (the smallest one if none does);
    lines between the cells are a frame and a gap of one."""
    shapes = [MapShape(rows, cols, cell_w, cell_h, axes=axes, gap=int(lines), row_gap=int(lines),
                       frame=lines)
              for cell_w, cell_h, lines in CELL_SHAPES
              for axes in (True, False) if not (axes and cell_w < len(str(rows - 1)))]
    return next((shape for shape in shapes if shape_fits(shape, width, height, 0)), shapes[-1])


class GridBoard(MapBoard):
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
    GridBoard .grid--caption { color: $text-muted; }
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
    EMPTY = "No grid yet."
    CAPTION_LINES = 0

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.trail: dict[Cell, str] = {}  # cell the agent left -> arrow of that move
        self._grid_agent: Cell | None = None
        self._grid_target: Cell | None = None
        self._grid_size = 0
        self._grid_walls: frozenset[Cell] = frozenset()
        self._laid_out: tuple[Any, int] | None = None  # (terminal size, board width) last seen

    def on_resize(self, event: events.Resize) -> None:
        # A new terminal size, or a new width (the layout around the board changed, or
        # is settling after a resize): the cell shape is chosen afresh. Lines of text
        # coming and going above or below change only the board's height.
        laid_out = (self.app.size, event.size.width)
        if laid_out != self._laid_out:
            self._laid_out = laid_out
            self._shape = None
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
        """The next scene begins a new episode: forget the trail (the cells keep their size)."""
        self._fresh = True

    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        agent, target = cell_of(scene.get("agent")), cell_of(scene.get("target"))
        size = int(scene.get("size", 0))
        previous = self._grid_agent
        jumped = (
            previous is None
            or agent is None
            or abs(agent[0] - previous[0]) + abs(agent[1] - previous[1]) > 1
        )
        if self._fresh or jumped or target != self._grid_target or size != self._grid_size:
            self.trail = {}
        elif agent != previous and previous is not None and agent is not None:
            move = (agent[0] - previous[0], agent[1] - previous[1])
            self.trail[previous] = MOVES[move][1]
        self._fresh = False
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

    def map_size(self) -> tuple[int, int] | None:
        return (self._grid_size, self._grid_size) if self._grid_size > 0 else None

    choose_shape = staticmethod(choose_shape)

    def draw_map(self, shape: MapShape, width: int, spare: int) -> list[Text]:
        n, cw, ch, lines = shape.rows, shape.cell_w, shape.cell_h, shape.frame
        line, axis = self._style("line"), self._style("axis")
        grid = CharGrid(shape.width, shape.height, Style())
        left = shape.label_w
        if lines:
            for r in range(n + 1):  # the rules above, between and below the rows
                first, middle, last = "┌┬┐" if r == 0 else "└┴┘" if r == n else "├┼┤"
                rule = first + middle.join("─" * cw for _ in range(n)) + last
                grid.put(left, r * (ch + 1), rule, line)
        for row in range(n):
            y, top = n - 1 - row, shape.y_of(row)
            if shape.axes:
                grid.put(0, top + ch // 2, f"{y:>{left - 1}}", axis)
            for x in range(n):
                glyph, style = self._cell_look((x, y), lines)
                fill = WALL if glyph == WALL else " "  # a wall fills its cell
                grid.fill(shape.x_of(x), top, cw, ch, fill, style)
                if fill == " ":
                    grid.put(shape.x_of(x), top + ch // 2, glyph.center(cw), style)
            for c in range(n + 1 if lines else 0):  # the bars beside the cells
                grid.fill(left + c * (cw + 1), top, 1, ch, "│", line)
        if shape.axes:
            for x in range(n):
                grid.put(shape.x_of(x), shape.height - 1, str(x).center(cw), axis)
        return grid.lines()

    def canvas_clicked(self, offset: Offset) -> None:
        """Step one cell towards the clicked cell (the longer way first)."""
        cell = self.layout_drawn.cell_at(offset) if self.layout_drawn else None
        if cell is not None and self._grid_agent is not None:
            x, y = self._grid_agent
            self.step_to((self._grid_size - 1 - y, x), cell, ROW_MOVES)
