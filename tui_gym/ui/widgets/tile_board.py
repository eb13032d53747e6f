"""`TileBoard`: a map of tiles: FrozenLake's ice, CliffWalking's cliff, edited grid maps.

Scene keys: "cells" (S F H G C W R rows), "theme", "agent", "last_action", "slipped",
"rewards", "slip", "marks", "cursor", "event"/"event_tone", "wind"/"gusts", "moves",
"offered", "choices"; cells are (row, col) or "r,c", row 0 at the top.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

from rich.color import Color
from rich.style import Style
from rich.text import Text
from textual.binding import Binding, BindingType
from textual.geometry import Offset
from textual.message import Message

from tui_gym.games.words import format_reward
from tui_gym.ui.widgets.board_drawing import (
    Cell,
    CharGrid,
    MapBoard,
    MapShape,
    cell_of,
    legend,
    listed,
    on_tile,
    read_as,
    shape_fits,
)
from tui_gym.ui.widgets.boards import NEW_EPISODE_HELP, NEW_EPISODE_KEYS, arrow_bindings
from tui_gym.ui.widgets.numbers import fit
from tui_gym.ui.widgets.strip_widget import component_classes

START, FLOOR, HOLE, GOAL, CLIFF, WALL, REWARD = "S", "F", "H", "G", "C", "W", "R"
KINDS = (START, FLOOR, HOLE, GOAL, CLIFF, WALL, REWARD)  # the legend's order
FILLED = frozenset({CLIFF, WALL})  # drawn as a texture over the whole tile
GLYPHS = {START: "⌂", FLOOR: "·", HOLE: "○", GOAL: "★", CLIFF: "▒", WALL: "█"}
GROUNDS = {HOLE: "hole", GOAL: "goal", CLIFF: "cliff", WALL: "wall"}  # a tile's own style
AGENT = "●"
AGENT_STYLES = {GOAL: "agent-home", HOLE: "agent-lost", CLIFF: "agent-lost"}  # else "agent"

STRAIGHT: dict[str, Cell] = {"left": (0, -1), "down": (1, 0), "right": (0, 1), "up": (-1, 0)}
MOVES: dict[str, Cell] = {**STRAIGHT, "up-left": (-1, -1), "up-right": (-1, 1),
                          "down-left": (1, -1), "down-right": (1, 1)}
MOVE_OF: dict[Cell, str] = {step: name for name, step in MOVES.items()}
ARROWS = {"left": "←", "down": "↓", "right": "→", "up": "↑",
          "up-left": "↖", "up-right": "↗", "down-left": "↙", "down-right": "↘"}
# The keypad's digits, as the moves they point to.
KEYPAD = {7: "up-left", 8: "up", 9: "up-right", 4: "left", 6: "right",
          1: "down-left", 2: "down", 3: "down-right"}
WIND = "↑"


@dataclass(frozen=True)
class Theme:
    """The words and floor colours of one kind of map."""

    title: str
    floor: str  # component class of the floor, and its name in the legend
    hole: str  # what a hole is called
    fell_in: str  # '{who} ...' on landing in a hole
    slipped: str  # '{who} ...' on a slip


THEMES = {
    "lake": Theme("Frozen lake", "ice", "hole", "fell through the ice", "slipped on the ice"),
    "cliff": Theme("Cliff", "ground", "pit", "fell into a pit", "slipped"),
    "plain": Theme("Map", "floor", "pit", "fell into a pit", "slipped"),
}

TONES = ("good", "bad", "slipped", "caption")  # the styles a scene's event may take
Event = tuple[tuple[str, ...], str]  # what a move did: ('{who} ...' longest first), its style


TILE_SIZES = ((11, 5), (9, 4), (7, 3), (5, 2), (3, 1), (2, 1), (1, 1))
HALF_WIDTHS = (2, 1)


def choose_shape(rows: int, cols: int, width: int, height: int) -> MapShape:
    """The largest drawing of a rows x cols map that fits (the smallest one if none does)."""
    shapes = [
        *(MapShape(rows, cols, cell_w, cell_h, axes=axes) for cell_w, cell_h in TILE_SIZES
          for axes in (True, False) if not (axes and cell_w < len(str(cols - 1)))),
        *(MapShape(rows, cols, cell_w, 1, half=True) for cell_w in HALF_WIDTHS),
    ]
    return next((shape for shape in shapes if shape_fits(shape, width, height)), shapes[-1])


def cell_table(value: Any) -> dict[Cell, Any]:
    """A scene's {cell: value} table with its keys read as cells (bad keys dropped)."""
    if not isinstance(value, Mapping):
        return {}
    return {cell: item for key, item in value.items() if (cell := cell_of(key)) is not None}


class TileBoard(MapBoard):
    """A map of tiles (lake, cliff, plain): walk the agent ● to the goal ★."""

    STYLE = "tile"
    EMPTY = "No map yet."

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    TileBoard .tile--ice { background: #d3e9f5; color: #8fb3cc; }
    TileBoard .tile--ice-alt { background: #c2dfef; color: #8fb3cc; }
    TileBoard .tile--ground { background: #c3d69c; color: #8a9e66; }
    TileBoard .tile--ground-alt { background: #b8cd8f; color: #8a9e66; }
    TileBoard .tile--floor { background: #d9d9d4; color: #a3a39c; }
    TileBoard .tile--floor-alt { background: #cfcfc9; color: #a3a39c; }
    TileBoard .tile--start { color: #3b4b5c; text-style: bold; }
    TileBoard .tile--hole { background: #173a5c; color: #8cc3ea; text-style: bold; }
    TileBoard .tile--goal { background: #e0ac2b; color: #3a2a00; text-style: bold; }
    TileBoard .tile--cliff { background: #6e3b26; color: #9c5f43; }
    TileBoard .tile--wall { background: #3e4047; color: #5d6069; }
    TileBoard .tile--reward { background: #3f9b5a; color: #ffffff; text-style: bold; }
    TileBoard .tile--penalty { background: #b8473c; color: #ffffff; text-style: bold; }
    TileBoard .tile--agent { background: #1f7ae0; color: #ffffff; text-style: bold; }
    TileBoard .tile--agent-home { background: $success; color: #ffffff; text-style: bold; }
    TileBoard .tile--agent-lost { background: $error; color: #ffffff; text-style: bold; }
    TileBoard .tile--trail { color: #1d5e9e; text-style: bold; }
    TileBoard .tile--mark { color: #1b1b1b; text-style: bold; }
    TileBoard .tile--value { color: #ffffff; text-style: bold; }
    TileBoard .tile--slip { color: #4d87b3; }
    TileBoard .tile--wind { color: #5b6f86; text-style: bold; }
    TileBoard .tile--cursor { background: $accent; color: $text; text-style: bold; }
    TileBoard .tile--axis { color: $text-muted; }
    TileBoard .tile--caption { color: $text-muted; }
    TileBoard .tile--slipped { color: $text-warning; text-style: bold; }
    TileBoard .tile--good { color: $text-success; text-style: bold; }
    TileBoard .tile--bad { color: $text-error; text-style: bold; }
    """

    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    BINDINGS: ClassVar[list[BindingType]] = [
        *arrow_bindings("up", "down", "left", "right", "Move"),
        Binding("home", "act('up-left')", "up-left", show=False),
        Binding("pageup", "act('up-right')", "up-right", show=False),
        Binding("end", "act('down-left')", "down-left", show=False),
        Binding("pagedown", "act('down-right')", "down-right", show=False),
        *(Binding(str(d), f"digit({d})", str(d), show=False) for d in range(10)),
        *NEW_EPISODE_KEYS,
    ]

    BUTTONS = (("↺ Reset [dim]r[/]", "new_episode"),)

    @dataclass
    class CellClicked(Message):
        """A person clicked map cell (row, col) (an editor paints it; play steps towards it)."""

        row: int
        col: int

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.trail: dict[Cell, str] = {}  # cell the agent left -> arrow of that move
        self.agent: Cell | None = None
        self._read({})

    # --- what the board says ---------------------------------------------------
    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("↑ ↓ ← →  or  w a s d", "move up, down, left, right"),
            ("home pgup end pgdn", "king's moves: up-left, up-right, down-left, down-right"),
            ("1-9, 0", "the keypad's way (king's moves), or the choice of that number"),
            *NEW_EPISODE_HELP,
            ("click a cell", "step one cell towards it"),
        ]

    def action_act(self, action: str) -> None:
        """A move, unless the state offers others only (the caption then says which)."""
        if self.offered is not None and action not in self.offered and not self.agent_playing:
            shown = ", ".join(self.offered[:4]) + (" ..." if len(self.offered) > 4 else "")
            self._event = (f"No {action} here: the moves are {shown}", f"No {action} here"), \
                "slipped"
            self.redraw()
            return
        super().action_act(action)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Diagonals on a map with king's moves only, digits where they pick something: other
        keys go on to whoever else takes them."""
        if action == "act" and parameters and parameters[0] not in STRAIGHT:
            return self.king
        if action == "digit":
            return bool(self.choices) or self.king
        return True

    def action_digit(self, digit: int) -> None:
        """A digit: the scene's choice of that number (0 the tenth), else the keypad's move."""
        if self.choices:
            index = (digit - 1) % 10
            if index < len(self.choices):
                self.action_act(self.choices[index])
        elif digit in KEYPAD:
            self.action_act(KEYPAD[digit])

    prompt = "Move with the arrows or WASD, or click a cell; r starts over."
    over_hint = "This episode is over: press n, r or Enter (or click Reset) for a new one."

    def button_suggested(self, action: str) -> bool:
        return self.episode_over

    # --- the scene ---------------------------------------------------------------
    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        drawn = (self.cells, self.theme)
        self._read(scene)
        if (self.cells, self.theme) != drawn:
            self._fresh = True
        previous = None if self._fresh else self.agent
        agent = cell_of(scene.get("agent"))
        action = scene.get("last_action")
        action = action if action in MOVES else None
        self._event = self._event_of(previous, agent, action, bool(scene.get("slipped")))
        if scene.get("event"):
            tone = str(scene.get("event_tone", "good"))
            self._event = (str(scene["event"]),), tone if tone in TONES else "good"
        if self._fresh or previous is None or agent is None:
            self.trail = {}
        elif agent != previous:
            step = (agent[0] - previous[0], agent[1] - previous[1])
            if step in MOVE_OF:
                self.trail[previous] = ARROWS[MOVE_OF[step]]
            elif self.wind and action is not None:  # blown on: the move that was asked
                self.trail[previous] = ARROWS[action]
            else:  # a jump (back to the start after a fall): the walk starts over
                self.trail = {}
        self.agent = agent
        self._fresh = False
        super().show_scene(scene, reveal)

    def _read(self, scene: Mapping[str, Any]) -> None:
        """The map and what lies on it, from a scene."""
        rows = [str(row) for row in scene.get("cells") or ()]  # equal rows, as games give them
        self.cells = rows if any(rows) else []
        self.theme = THEMES.get(str(scene.get("theme", "lake")), THEMES["plain"])
        self.border_title = self.theme.title
        self.rewards = cell_table(scene.get("rewards"))
        self.slip = cell_table(scene.get("slip"))
        self.marks = {cell: str(text) for cell, text in cell_table(scene.get("marks")).items()}
        self.wind = [int(w) for w in listed(scene.get("wind")) if read_as(float, w) is not None]
        self.gusts = bool(scene.get("gusts"))
        offered = scene.get("offered")
        self.offered = None if offered is None else [str(a) for a in listed(offered)]
        self.choices = [str(a) for a in listed(scene.get("choices"))]
        self.king = "up-left" in listed(scene.get("moves"))  # the diagonals are moves
        self.cursor = cell_of(scene.get("cursor"))

    def kind(self, cell: Cell) -> str:
        """The map character at a cell ('' off the map)."""
        row, col = cell
        if 0 <= row < len(self.cells) and 0 <= col < len(self.cells[row]):
            return self.cells[row][col]
        return ""

    def _event_of(
        self, previous: Cell | None, agent: Cell | None, action: str | None, slipped: bool
    ) -> Event | None:
        """What the last move did, in words from longest to shortest, and their style."""
        if agent is None:
            return None
        kind, theme = self.kind(agent), self.theme
        if kind == HOLE:
            if slipped:
                return (
                    f"{{who}} {theme.slipped} into a {theme.hole}", f"Slipped into a {theme.hole}",
                ), "bad"
            return (f"{{who}} {theme.fell_in}", theme.fell_in.capitalize()), "bad"
        if kind == GOAL:
            if slipped:
                return (f"{{who}} {theme.slipped} onto the goal", "Slipped onto the goal"), "good"
            return ("{who} reached the goal", "Reached the goal"), "good"
        if previous is None or action is None:
            return None
        step = MOVES[action]
        intended = (previous[0] + step[0], previous[1] + step[1])
        if not self.kind(intended):
            intended = previous  # the edge of the map
        if self._fell(previous, agent, intended, slipped):
            return ("{who} fell off the cliff: back to the start", "Fell off the cliff"), "bad"
        if slipped:
            went = MOVE_OF.get((agent[0] - previous[0], agent[1] - previous[1]))
            outcome = f"went {went}" if went else "stayed put" if agent == previous else "moved"
            short = f"{action} → {went or ('stayed' if agent == previous else '?')}"
            texts: tuple[str, ...] = (
                f"{{who}} {theme.slipped}: asked {action}, {outcome}",
                f"Slipped: asked {action}, {outcome}", f"Slipped: {short}",
            )
            return texts, "slipped"
        if agent == previous:
            blocker = "a wall" if self.kind(intended) == WALL else "the edge"
            return (
                f"{{who}} bumped into {blocker} (asked {action})", f"Bumped into {blocker}",
            ), "caption"
        return (f"{{who}} moved {action}", f"Moved {action}"), "caption"

    def _fell(self, previous: Cell, agent: Cell, intended: Cell, slipped: bool) -> bool:
        """Whether the agent fell off a cliff and was sent back to the start."""
        if self.kind(agent) != START or agent == intended:
            return False
        if self.kind(intended) == CLIFF:
            return True
        far = abs(agent[0] - previous[0]) + abs(agent[1] - previous[1]) > 1
        beside = (
            self.kind((previous[0] + dr, previous[1] + dc)) == CLIFF
            for dr, dc in STRAIGHT.values()
        )
        return far and slipped and any(beside)

    # --- drawing -----------------------------------------------------------------
    def _reward(self, cell: Cell) -> float | None:
        return read_as(float, self.rewards.get(cell))

    def _ground(self, cell: Cell, kind: str) -> Style:
        """The style of a tile's background (and of its glyph, unless it has its own)."""
        if kind in GROUNDS:
            return self._style(GROUNDS[kind])
        if kind == REWARD:
            value = self._reward(cell)
            return self._style("penalty" if value is not None and value < 0 else "reward")
        floor = self.theme.floor
        return self._style(f"{floor}-alt" if (cell[0] + cell[1]) % 2 else floor)

    def _glyph(self, cell: Cell, kind: str, width: int) -> str:
        """A tile's glyph, at most `width` characters."""
        if kind == REWARD:
            value = self._reward(cell)
            text = format_reward(value) if value is not None else "◆"
            if len(text) > width:
                text = "−" if value is not None and value < 0 else "+"
            return text
        return GLYPHS.get(kind, kind)[:width]

    def _paint_tile(self, grid: CharGrid, cell: Cell, shape: MapShape) -> None:
        w, h = shape.cell_w, shape.cell_h
        x0, y0 = shape.x_of(cell[1]), shape.y_of(cell[0])
        kind = self.kind(cell)
        tile = self._ground(cell, kind)
        mid = h // 2
        big = w >= 7 and h >= 3  # room for a rounded agent
        pool = w >= 7 and h >= 4  # room for a rounded hole in the floor, and its value
        if kind in FILLED:
            grid.fill(x0, y0, w, h, GLYPHS[kind], tile)
        elif kind == HOLE and pool:
            floor = self._ground(cell, FLOOR)
            grid.fill(x0, y0, w, h, " ", floor)
            grid.pill(x0 + 1, y0, w - 2, h, tile, floor)
        else:
            grid.fill(x0, y0, w, h, " ", tile)
        glyph = self._glyph(cell, kind, w)
        ink = on_tile(self._style("start"), tile) if kind == START else tile
        if cell in self.marks:
            glyph, ink = self.marks[cell][:w], on_tile(self._style("mark"), tile)
        if cell in self.trail:
            glyph, ink = self.trail[cell], on_tile(self._style("trail"), tile)
        if kind not in FILLED or glyph != GLYPHS[kind]:
            grid.put(x0 + (w - len(glyph)) // 2, y0 + mid, glyph, ink)
        value = self._reward(cell)
        if h >= 2 and value is not None and kind != REWARD:
            text = format_reward(value)
            if len(text) <= w:
                below = mid + 1 < (h - 1 if kind == HOLE and pool else h)
                line = mid + 1 if below else mid - 1
                value_ink = on_tile(self._style("value"), tile)
                grid.put(x0 + (w - len(text)) // 2, y0 + line, text, value_ink)
        slip = read_as(float, self.slip.get(cell))
        if slip and w >= 5 and kind not in FILLED:
            grid.put(x0 + w - 1, y0, "≈", on_tile(self._style("slip"), tile))
        wind = self.wind[cell[1]] if cell[1] < len(self.wind) else 0
        if wind > 0 and w >= 5 and kind not in FILLED:
            grid.put(x0, y0, WIND * min(wind, w - 2), on_tile(self._style("wind"), tile))
        if cell == self.agent:
            agent = self._style(AGENT_STYLES.get(kind, "agent"))
            if big:
                under = grid.styles[y0 + mid][x0]
                grid.pill(x0 + (w - 5) // 2, y0 + mid - 1, 5, 3, agent, under)
                grid.put(x0 + w // 2, y0 + mid, AGENT, agent)
            else:
                chip = min(w, 3)
                grid.put(x0 + (w - chip) // 2, y0 + mid, AGENT.center(chip), agent)
        if cell == self.cursor:
            self._paint_cursor(grid, x0, y0, w, h)

    def _paint_cursor(self, grid: CharGrid, x0: int, y0: int, w: int, h: int) -> None:
        """The editing cursor: corners around the tile, or the whole tile when narrow."""
        cursor = self._style("cursor")
        if w < 3:
            for line in range(y0, y0 + h):
                grid.put(x0, line, "".join(grid.chars[line][x0 : x0 + w]), cursor)
        elif h == 1:
            grid.put(x0, y0, "[", cursor)
            grid.put(x0 + w - 1, y0, "]", cursor)
        else:
            for x, y, corner in ((0, 0, "┌"), (1, 0, "┐"), (0, 1, "└"), (1, 1, "┘")):
                grid.put(x0 + x * (w - 1), y0 + y * (h - 1), corner, cursor)

    def _swatch(self, cell: Cell) -> Color | None:
        """A cell's colour in the half drawing."""
        kind = self.kind(cell)
        if cell == self.agent:
            return self._style(AGENT_STYLES.get(kind, "agent")).bgcolor
        if cell == self.cursor:
            return self._style("cursor").bgcolor
        if kind == START:
            return self._style("start").color
        return self._ground(cell, kind).bgcolor

    def map_size(self) -> tuple[int, int] | None:
        return (len(self.cells), len(self.cells[0])) if self.cells else None

    choose_shape = staticmethod(choose_shape)

    def lines_under(self) -> int:
        return 1 if self.wind else 0  # a line kept for the wind under the columns

    def draw_map(self, shape: MapShape, width: int, spare: int) -> list[Text]:
        w, h = shape.cell_w, shape.cell_h
        grid = CharGrid(shape.width, shape.height, Style())
        if shape.half:
            for line in range(shape.map_h):
                for col in range(shape.cols):
                    top = self._swatch((2 * line, col))
                    below = self._swatch((2 * line + 1, col)) if 2 * line + 1 < shape.rows else None
                    grid.put(shape.x_of(col), line, "▀" * w, Style(color=top, bgcolor=below))
            return grid.lines()
        for row in range(shape.rows):
            for col in range(shape.cols):
                self._paint_tile(grid, (row, col), shape)
        if shape.axes:
            axis = self._style("axis")
            for row in range(shape.rows):
                grid.put(0, row * h + h // 2, f"{row:>{shape.label_w - 1}}", axis)
            for col in range(shape.cols):
                grid.put(shape.x_of(col), shape.map_h, str(col).center(w), axis)
        lines = grid.lines()
        if self.wind and spare > 0:
            lines.append(self._wind_line(shape))
        return lines

    def caption(self, width: int) -> Text:
        """What the last move did, or where the cursor or the agent is, in words that fit."""
        spot = self.cursor or self.agent
        if self._event is not None:
            texts, style = self._event
        elif spot is not None:
            who, (row, col) = ("Cursor" if self.cursor else "{who}"), spot
            texts = (f"{who} at row {row}, column {col}", f"{who} at ({row}, {col})")
            style = "caption"
        else:
            return Text("")
        said = [text.format(who=self.player_name) for text in texts]
        caption = Text(fit(said, width), self._style(style))
        caption.truncate(width, overflow="ellipsis")
        return caption

    def legend(self, width: int) -> Text | None:
        """'⌂ start  · ice  ○ hole  ★ goal  ● you': the tiles this map has (None if too wide)."""
        present = {kind for row in self.cells for kind in row}
        words = {
            START: "start", FLOOR: self.theme.floor, HOLE: self.theme.hole, GOAL: "goal",
            CLIFF: "cliff", WALL: "wall", REWARD: "reward",
        }
        items = []
        for kind in KINDS:
            if kind in present:
                tile = self._ground((0, 0), kind)
                ink = on_tile(self._style("start"), tile) if kind == START else tile
                items.append(("◆" if kind == REWARD else GLYPHS[kind], ink, words[kind]))
        if self.agent is not None:
            items.append((AGENT, self._style("agent"), self.player_name.lower()))
        if any(self.wind):
            items.append((WIND, self._style("wind"), "wind ±1" if self.gusts else "wind"))
        return legend(items, self._style("caption"), width)

    def _wind_line(self, shape: MapShape) -> Text:
        """Each column's wind under it, as the book draws it."""
        line = Text(" " * shape.label_w, end="")
        for col in range(shape.cols):
            strength = self.wind[col] if col < len(self.wind) else 0
            text = f"{WIND}{strength}" if strength and shape.cell_w >= 3 else str(strength)
            line.append(text[: shape.cell_w].center(shape.cell_w),
                        self._style("wind" if strength else "axis"))
        return line

    # --- keys and clicks -----------------------------------------------------------
    def canvas_clicked(self, offset: Offset) -> None:
        cell = self.layout_drawn.cell_at(offset, self.agent) if self.layout_drawn else None
        if cell is not None:  # the agent steps one cell towards it
            self.post_message(self.CellClicked(*cell))
            self.step_to(self.agent, cell, MOVE_OF)


__all__ = ["MOVES", "THEMES", "TileBoard", "choose_shape"]
