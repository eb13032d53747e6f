"""Drawing helpers for the map boards (`TileBoard`, `TaxiBoard`)."""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from typing import Any, Generic, TypeVar

from rich.style import Style
from rich.text import Text

Cell = tuple[int, int]  # (row, col), row 0 at the top
Shape = TypeVar("Shape")


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

    def style_at(self, x: int, y: int) -> Style:
        return self.styles[y][x]

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


def stack(lines: Sequence[Text], width: int, height: int) -> Text:
    """Lines as one picture: each line centred across `width`, the block centred in `height`."""
    out = Text(no_wrap=True, overflow="crop", end="")
    out.append("\n" * max(0, (height - len(lines)) // 2))
    for i, line in enumerate(lines):
        if i:
            out.append("\n")
        out.append(" " * max(0, (width - line.cell_len) // 2))
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


class KeptShape(Generic[Shape]):
    """The drawing shape a board keeps while it fits (see the module docstring)."""

    def __init__(self) -> None:
        self._shape: Shape | None = None
        self._key: Hashable = None

    def release(self) -> None:
        """Choose afresh at the next drawing (a new episode may take the best fit)."""
        self._shape = None

    def get(
        self, key: Hashable, width: int, height: int, choose: Callable[[int, int], Shape],
        fits: Callable[[Shape, int, int], bool],
    ) -> Shape:
        """The kept shape if the map (`key`) and width are the same and it still fits,
        else `choose(width, height)`, kept from now on."""
        kept = self._shape
        if kept is not None and self._key == (key, width) and fits(kept, width, height):
            return kept
        shape = choose(width, height)
        self._shape, self._key = shape, (key, width)
        return shape


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


def reward_text(value: float) -> str:
    """A reward for people: '+5', '−100' (a true minus sign), '0', '+0.5'."""
    if value == 0:
        return "0"
    return ("+" if value > 0 else "\u2212") + f"{abs(value):.4g}"


__all__ = [
    "Cell", "CharGrid", "KeptShape", "cell_of", "legend", "on_tile", "reward_text", "stack",
    "step_toward",
]
