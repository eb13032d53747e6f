"""`JumpScreen`: ask for the number of the episode to jump to in a replay."""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Input, Static

from tui_gym.ui.widgets.text_field import TextField


class JumpScreen(ModalScreen[int | None]):
    """Type an episode number (1 to `count`); enter jumps, escape cancels."""

    DEFAULT_CSS = """
    JumpScreen { align: center middle; }
    JumpScreen > Vertical {
        width: 48; max-width: 100%; height: auto;
        border: thick $primary; background: $surface; padding: 1 2;
    }
    JumpScreen #jump-title { text-style: bold; color: $accent; }
    JumpScreen #jump-error { color: $text-error; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "dismiss", "Cancel", show=False)]

    def __init__(self, count: int, current: int, noun: str = "episode") -> None:
        super().__init__()
        self.count = count
        self.current = current
        self.noun = noun

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(f"Jump to {self.noun} (1 to {self.count:,})"), id="jump-title")
            yield TextField(str(self.current), placeholder=f"a number, 1 to {self.count}",
                        id="jump-number", type="integer")
            yield Static("", id="jump-error")

    def on_mount(self) -> None:
        field = self.query_one(Input)
        field.focus()
        field.select_all()

    @property
    def error(self) -> str:
        return str(self.query_one("#jump-error", Static).render())

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        text = event.value.strip()
        number = int(text) if text.isascii() and text.lstrip("-").isdigit() else None
        if number is None or not 1 <= number <= self.count:
            self.query_one("#jump-error", Static).update(
                Text(f"✗ Type a number from 1 to {self.count:,}.")
            )
            return
        self.dismiss(number)
