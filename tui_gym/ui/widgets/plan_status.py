"""`PlanStatus`: the Plan view's lines of words, drawn from kept lines on every sweep."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from rich.segment import Segment

from tui_gym.ui.widgets.numbers import cut
from tui_gym.ui.widgets.strip_widget import Line, StripWidget

__all__ = ["PlanStatus"]

STYLES = ("plan-status--settings", "plan-status--state", "plan-status--meaning",
          "plan-status--note")


class PlanStatus(StripWidget):
    """The planner's settings, state, the value shown and a warning, a line each."""

    COMPONENT_CLASSES: ClassVar[set[str]] = set(STYLES)
    DEFAULT_CSS = """
    PlanStatus { height: 4; width: 1fr; }
    Screen.compact PlanStatus { height: 3; }
    PlanStatus > .plan-status--settings { color: $text-muted; }
    PlanStatus > .plan-status--state { color: $text; text-style: bold; }
    PlanStatus > .plan-status--meaning { color: $text-muted; }
    PlanStatus > .plan-status--note { color: $text-warning; }
    """

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self.lines: tuple[str, ...] = ("", "", "", "")

    def show(self, lines: Sequence[str]) -> None:
        """Settings, state, meaning and note (each may be '')."""
        lines = tuple(lines)
        if lines != self.lines:
            self.lines = lines
            self.redraw()

    @property
    def plain(self) -> str:
        return "\n".join(self.lines)

    def draw(self, width: int) -> list[Line]:
        styles = self.component_styles()
        shown = [(text, style) for text, style in zip(self.lines, STYLES, strict=True)
                 if not (self._compact() and style == "plan-status--meaning")]
        return [[Segment(cut(text, width), styles[style])] for text, style in shown]
