"""`MapBoard`, the base of the map boards (`TileBoard`, `TaxiBoard`), and their drawing
helpers."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from rich.style import Style
from rich.text import Text
from textual.geometry import Offset

from tui_gym.ui.widgets.boards import Board

Cell = tuple[int, int]  # (row, col), row 0 at the top
T = TypeVar("T")
CAPTION_LINES = 1  # the line under the map is always kept free: tiles keep their size


class CharGrid:
    """A `width` x `height` rectangle of characters, each with its own style."""

    def __init__(self, width: int, height: int, style: Style) -> None:
        self.width = width
        self.height = height
        self.chars = [[" "] * width for _ in range(height)]
        self.styles = [[style] * width for _ in range(height)]

    def put(self, x: int, y: int, text: str, style: Style) -> None:
        """Write `text` from column `x` of line `y` (what falls outside is dropped)."""
        if not 0 <= y < self.height:
            return
        chars, styles = self.chars[y], self.styles[y]
        for i, char in enumerate(text):
            if 0 <= x + i < self.width:
                chars[x + i] = char
                styles[x + i] = style

    def fill(self, x: int, y: int, width: int, height: int, char: str, style: Style) -> None:
        """Fill a rectangle with one character in one style."""
        for line in range(y, y + height):
            self.put(x, line, char * width, style)

    def pill(self, x: int, y: int, width: int, height: int, colour: Style, under: Style) -> None:
        """A block of `colour`'s background with rounded ends: its first and last lines
        are half blocks over `under`'s background (so it looks `height - 1` lines tall)."""
        if height < 3:
            self.fill(x, y, width, height, " ", colour)
            return
        edge = Style(color=colour.bgcolor, bgcolor=under.bgcolor)
        self.put(x, y, "▗" + "▄" * (width - 2) + "▖", edge)
        self.fill(x, y + 1, width, height - 2, " ", colour)
        self.put(x, y + height - 1, "▝" + "▀" * (width - 2) + "▘", edge)

    def lines(self) -> list[Text]:
        """The grid as Rich lines, one segment per run of equal style."""
        out = []
        for chars, styles in zip(self.chars, self.styles, strict=True):
            line = Text(no_wrap=True, end="")
            start = 0
            for i in range(1, self.width + 1):
                if i == self.width or styles[i] != styles[start]:
                    line.append("".join(chars[start:i]), styles[start])
                    start = i
            out.append(line)
        return out


def on_tile(ink: Style, tile: Style) -> Style:
    """`ink`'s colour and attributes over `tile`'s background."""
    return tile + Style(color=ink.color) + ink.without_color


def stack(lines: Sequence[Text], width: int, height: int, block: bool = False) -> Text:
    """Lines as one picture, centred in `height`: each line centred across `width`, or
    with `block` the lines left-aligned among themselves and centred together."""
    widest = max((line.cell_len for line in lines), default=0)
    out = Text(no_wrap=True, overflow="crop", end="")
    out.append("\n" * max(0, (height - len(lines)) // 2))
    for i, line in enumerate(lines):
        if i:
            out.append("\n")
        out.append(" " * max(0, (width - (widest if block else line.cell_len)) // 2))
        out.append_text(line)
    return out


def legend(items: Sequence[tuple[str, Style, str]], label: Style, width: int) -> Text | None:
    """'⌂ start  ○ hole  ★ goal' from (glyph, its style, word) items, in the widest
    form that fits `width` (None if none does)."""
    for pad, gap in ((" ", "  "), ("", "  "), ("", " ")):
        line = Text(end="")
        for i, (glyph, style, word) in enumerate(items):
            if i:
                line.append(gap)
            line.append(f"{pad}{glyph}{pad}", style)
            line.append(f" {word}", label)
        if line.cell_len <= width:
            return line
    return None


@dataclass(frozen=True)
class MapShape:
    """How big a map is drawn: `cell_w` x `cell_h` characters a tile; `half`: two map rows
    share a line (colour only); `axes`: row numbers left, column numbers below; `gap`,
    `row_gap`: columns and lines between tiles (for walls, grid lines); `frame`: a wall all
    round."""

    rows: int
    cols: int
    cell_w: int
    cell_h: int
    half: bool = False
    axes: bool = False
    gap: int = 0
    row_gap: int = 0
    frame: bool = False

    @property
    def label_w(self) -> int:
        return len(str(self.rows - 1)) + 1 if self.axes else 0

    @property
    def edge(self) -> int:
        return 1 if self.frame else 0

    @property
    def map_h(self) -> int:
        if self.half:
            return (self.rows + 1) // 2
        return self.rows * (self.cell_h + self.row_gap) - self.row_gap

    @property
    def width(self) -> int:
        return self.label_w + self.cols * (self.cell_w + self.gap) - self.gap + 2 * self.edge

    @property
    def height(self) -> int:
        """Lines of the map, its frame and its column numbers (the caption comes under)."""
        return self.map_h + (1 if self.axes else 0) + 2 * self.edge

    def x_of(self, col: int) -> int:
        return self.label_w + self.edge + col * (self.cell_w + self.gap)

    def y_of(self, row: int) -> int:
        return self.edge + (row // 2 if self.half else row * (self.cell_h + self.row_gap))


def shape_fits(shape: MapShape, width: int, height: int, caption: int = CAPTION_LINES) -> bool:
    """Whether a map drawn in `shape` fits `width` x `height`, with its caption's lines."""
    return shape.width <= width and shape.height + caption <= height


@dataclass(frozen=True)
class MapLayout:
    """Where a drawn map sits in the canvas, to map clicks back to cells."""

    shape: MapShape
    left: int  # canvas column of the drawing's left edge
    top: int  # canvas line of the drawing's top edge

    def cell_center(self, cell: Cell) -> Offset:
        """The canvas offset of the middle of a cell."""
        shape, (row, col) = self.shape, cell
        return Offset(self.left + shape.x_of(col) + shape.cell_w // 2,
                      self.top + shape.y_of(row) + shape.cell_h // 2)

    def cell_at(self, offset: Offset, near: Cell | None = None) -> Cell | None:
        """The cell under a canvas offset (None off the cells); where a line holds two rows
        (a half drawing), the lower one when `near` (the agent) is on it or below."""
        shape = self.shape
        x, y = offset.x - self.left, offset.y - self.top
        cols = [col for col in range(shape.cols) if 0 <= x - shape.x_of(col) < shape.cell_w]
        rows = [row for row in range(shape.rows) if 0 <= y - shape.y_of(row) < shape.cell_h]
        if not cols or not rows:
            return None
        return (rows[-1] if near is not None and near[0] >= rows[-1] else rows[0]), cols[0]


class MapBoard(Board):
    """A map drawn in the largest shape that fits, kept while it fits (no jumps as the
    space around changes), with a caption under it (unless `CAPTION_LINES` is 0) and a
    legend when there is room."""

    EMPTY: ClassVar[str] = ""  # what the board says before it has a map
    CAPTION_LINES: ClassVar[int] = CAPTION_LINES  # 0: no caption under the map

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._event: Any = None  # what the last move did, in words
        self._fresh = True  # the next scene starts an episode
        self._shape: MapShape | None = None  # the shape kept, and the (map size, width) it is for
        self._shape_key: Hashable = None
        self.layout_drawn: MapLayout | None = None  # where the map was drawn, for clicks

    @property
    def event_text(self) -> str:
        """What the last move did, in words ('' when there is nothing to say)."""
        return self._event[0][0].format(who=self.player_name) if self._event else ""

    def start_episode(self) -> None:
        """The next scene begins a new episode; tiles may take a new size."""
        self._fresh = True
        self._shape = None

    # --- what a map board gives ---------------------------------------------
    def map_size(self) -> tuple[int, int] | None:
        """(rows, cols) of the map, or None before there is one."""
        return None

    def choose_shape(self, rows: int, cols: int, width: int, height: int) -> MapShape:
        """The largest drawing of the map that fits `width` x `height`."""
        raise NotImplementedError

    def draw_map(self, shape: MapShape, width: int, spare: int) -> list[Text]:
        """The map's lines in `shape` (`spare`: lines left over once the caption is in)."""
        raise NotImplementedError

    def caption(self, width: int) -> Text:
        """What the last move did, in words that fit `width`."""
        raise NotImplementedError

    def legend(self, width: int) -> Text | None:
        """The marks the map uses and what they mean (None if too wide)."""
        return None

    # --- drawing --------------------------------------------------------------
    def picture(self, width: int, height: int) -> Text:
        size = self.map_size()
        if size is None:
            self.layout_drawn = None
            return stack([Text(self.EMPTY, self._style("caption"))], width, height)
        shape, room = self._shape, height - self.lines_under()
        if not (self.KEEP_SHAPE and shape is not None and self._shape_key == (size, width)
                and shape_fits(shape, width, room, self.CAPTION_LINES)):
            shape = self.choose_shape(*size, width, room)
            self._shape, self._shape_key = shape, (size, width)
        spare = height - shape.height - self.CAPTION_LINES
        lines = self.draw_map(shape, width, spare)
        spare -= len(lines) - shape.height
        if self.CAPTION_LINES:
            lines.append(self.caption(width))
        if spare > 0:
            legend = self.legend(width)
            if legend is not None:
                lines.append(legend)
        left = max(0, (width - shape.width) // 2)
        top = max(0, (height - len(lines)) // 2)
        self.layout_drawn = MapLayout(shape, left, top)
        return stack(lines, width, height)

    def lines_under(self) -> int:
        """Lines kept under the map besides the caption (the wind's, say)."""
        return 0

    def step_to(self, origin: Cell | None, target: Cell, moves: dict[Cell, str]) -> None:
        """Move one cell from `origin` towards `target` (nothing when it is there)."""
        if origin is not None and target != origin:
            self.action_act(moves[step_toward(origin, target)])


def read_as(kind: Callable[[Any], T], value: Any) -> T | None:
    """`kind(value)` (a scene's number as an int or a float), or None where it is not one."""
    try:
        return kind(value)
    except (TypeError, ValueError):
        return None


def listed(value: Any) -> list[Any]:
    """A scene's list (anything else: empty)."""
    return list(value) if isinstance(value, list | tuple) else []


def cell_of(value: Any) -> Cell | None:
    """(row, col) from a (row, col) pair or a "r,c" string; None for anything else."""
    try:
        if isinstance(value, str):
            row, col = value.split(",")
        else:
            row, col = value
        return int(row), int(col)
    except (TypeError, ValueError):
        return None


def step_toward(origin: Cell, target: Cell) -> Cell:
    """The (d_row, d_col) step from `origin` towards another cell `target`, the longer way first."""
    d_row, d_col = target[0] - origin[0], target[1] - origin[1]
    if abs(d_col) >= abs(d_row):
        return 0, (1 if d_col > 0 else -1)
    return (1 if d_row > 0 else -1), 0


__all__ = [
    "CAPTION_LINES", "Cell", "CharGrid", "MapBoard", "MapLayout", "MapShape", "cell_of", "legend",
    "listed", "on_tile", "read_as", "shape_fits", "stack", "step_toward",
]
