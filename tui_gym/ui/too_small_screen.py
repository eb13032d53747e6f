"""`TooSmallScreen`: what shows while the terminal is smaller than the app needs."""

from __future__ import annotations

from typing import ClassVar

from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.screen import ModalScreen
from textual.widgets import Static


class TooSmallScreen(ModalScreen[None]):
    """Ask for a larger window; every key but quit is ignored meanwhile."""

    DEFAULT_CSS = """
    TooSmallScreen { align: center middle; background: $background; }
    TooSmallScreen #too-small {
        width: 100%; height: 100%; content-align: center middle; text-align: center;
        text-style: bold; color: $warning;
    }
    """

    BINDINGS: ClassVar[list[BindingType]] = [Binding("q", "app.quit", "Quit", show=False)]

    def __init__(self, min_width: int, min_height: int) -> None:
        super().__init__()
        self.min_width, self.min_height = min_width, min_height

    def compose(self) -> ComposeResult:
        yield Static(
            "The terminal is too small for tui-gym.\n"
            f"It needs at least {self.min_width}×{self.min_height}; make the window larger.\n"
            "(q quits)",
            id="too-small",
        )
