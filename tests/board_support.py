"""Shared by the board tests: a tiny app that mounts boards alone at given sizes, records
what they post, and reads their drawing back as text and styles."""

from __future__ import annotations

from collections.abc import Sequence

from rich.style import Style
from textual.app import App, ComposeResult
from textual.geometry import Offset

from tui_gym.ui.widgets.boards import Board

# Board sizes as the app gives them: Play view at 120x40 and at 80x24 (compact),
# the Train view's passive board at 120x40 and at 80x24.
PLAY_BIG = (74, 26)
PLAY_COMPACT = (46, 12)
TRAIN_BIG = (36, 7)
TRAIN_COMPACT = (24, 7)


class BoardApp(App[None]):
    """Boards stacked top to bottom, each at its own size; what they post is recorded."""

    CSS = "Screen { layout: vertical; }"

    def __init__(self, boards: Sequence[tuple[Board, tuple[int, int]]]) -> None:
        super().__init__()
        self.boards = boards
        self.posted: list[tuple] = []

    def compose(self) -> ComposeResult:
        for board, (width, height) in self.boards:
            board.styles.width = width
            board.styles.height = height
            yield board

    def on_board_act(self, message: Board.Act) -> None:
        self.posted.append(("act", message.action))

    def on_board_new_episode(self, message: Board.NewEpisode) -> None:
        self.posted.append(("new",))

    def on_board_take_over(self, message: Board.TakeOver) -> None:
        self.posted.append(("take over",))

    def on_tile_board_cell_clicked(self, message) -> None:
        self.posted.append(("cell", message.row, message.col))


def screen_height(boards: Sequence[tuple[Board, tuple[int, int]]]) -> int:
    return sum(height for _, (_, height) in boards)


def rows(board: Board) -> list[str]:
    """The board's drawing as plain text, one string per canvas line."""
    canvas = board.canvas
    return ["".join(s.text for s in line) for line in canvas.picture(canvas.content_size.width)]


def char_at(board: Board, offset: Offset) -> str:
    lines = rows(board)
    return (
        lines[offset.y][offset.x]
        if offset.y < len(lines) and offset.x < len(lines[offset.y])
        else ""
    )


def style_at(board: Board, offset: Offset) -> Style:
    """The Rich style of the drawing's character at a canvas offset."""
    canvas = board.canvas
    line = canvas.picture(canvas.content_size.width)[offset.y]
    x = 0
    for segment in line:
        if x <= offset.x < x + len(segment.text):
            return segment.style or Style()
        x += len(segment.text)
    raise IndexError(offset)


def text_of(board: Board) -> str:
    return "\n".join(rows(board))
