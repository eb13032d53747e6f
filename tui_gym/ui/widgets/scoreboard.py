"""`Scoreboard`: the person, the agent and the exact optimum, one row each."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

from rich.console import RenderableType
from rich.table import Table
from rich.text import Text
from textual.widget import Widget

from tui_gym.games.words import ScoreRow
from tui_gym.ui.widgets.strip_widget import component_classes


class Scoreboard(Widget):
    """You, the agent and the optimum side by side, as the game words them."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    Scoreboard {
        width: 1fr;
        height: auto;
        padding: 0 1;
        border: round $foreground 25%;
        border-title-color: $text-muted;
    }
    Scoreboard .scoreboard--who { text-style: bold; }
    Scoreboard .scoreboard--you { color: $text-primary; }
    Scoreboard .scoreboard--agent { color: $text-accent; }
    Scoreboard .scoreboard--optimum { color: $text-success; }
    Scoreboard .scoreboard--other { color: $text-muted; }
    Screen.compact Scoreboard { border: none; padding: 0 1; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    WHO_STYLES: ClassVar[dict[str, str]] = {"You": "you", "Agent": "agent", "Optimum": "optimum"}

    BORDER_TITLE = "Scoreboard"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.rows: tuple[ScoreRow, ...] = ()

    def show_rows(self, rows: Sequence[ScoreRow]) -> None:
        """Show these rows (redraws only when they changed)."""
        rows = tuple(rows)
        if rows != self.rows:
            self.rows = rows
            self.refresh(layout=True)

    def text(self, compact: bool = False) -> str:
        """The rows as plain lines ('You  …'), as they read on screen (in the compact layout
        with `compact`)."""
        width = max((len(row.who) for row in self.rows), default=0)
        return "\n".join(
            f"{row.who:<{width}}  {(row.short or row.text) if compact else row.text}"
            for row in self.rows
        )

    def render(self) -> RenderableType:
        if not self.rows:
            return Text("")
        short = self.is_attached and self.screen.has_class("compact")
        who_style = self.get_component_rich_style("scoreboard--who")
        grid = Table.grid(padding=(0, 2 if not short else 1), expand=True)
        grid.add_column(no_wrap=True)
        grid.add_column(ratio=1)
        for row in self.rows:
            kind = self.WHO_STYLES.get(row.who, "other")
            style = self.get_component_rich_style(f"scoreboard--{kind}")
            words = (row.short or row.text) if short else row.text
            grid.add_row(Text(row.who, who_style + style), Text(words))
        return grid
