"""`ProgressLine`: one line with a bar toward the episode budget and its numbers."""

from __future__ import annotations

from typing import ClassVar

from rich.segment import Segment

from tui_gym.ui.widgets.numbers import compact_count, fit
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, component_classes

DONE, HALF = "━", "╸"
MIN_BAR = 4  # cells: narrower than this, the bar is left out


class ProgressLine(StripWidget):
    """A bar toward the episode budget, the percentage, the counts and the time left."""

    DEFAULT_CSS = """
    ProgressLine { height: 1; width: 1fr; }
    ProgressLine > .progress--done { color: $accent; }
    ProgressLine > .progress--left { color: $foreground 10%; }
    ProgressLine > .progress--percent { color: $text; }
    ProgressLine > .progress--text { color: $text-muted; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.done = 0
        self.total = 1
        self.eta = ""

    @property
    def fraction(self) -> float:
        return min(1.0, max(0.0, self.done / self.total)) if self.total > 0 else 0.0

    def text(self, width: int | None = None) -> str:
        """The words after the bar: '60,000 / 200,000 episodes · eta 0:03'; with a
        `width`, the fullest form of them that fits in it."""
        eta = f" · eta {self.eta}" if self.eta else ""
        full = f"{self.done:,} / {self.total:,}"
        short = f"{compact_count(self.done)} / {compact_count(self.total)}"
        forms = [f"{full}{eta}", f"{short}{eta}", short]  # the time left goes last
        if not self._compact():
            forms.insert(0, f"{full} episodes{eta}")
        return forms[0] if width is None else fit(forms, width)

    def show(self, done: int, total: int, eta: str = "") -> None:
        """`done` of `total` episodes, and the time left while training runs ("" if not)."""
        if (done, total, eta) != (self.done, self.total, self.eta):
            self.done, self.total, self.eta = done, total, eta
            self.redraw()

    def draw(self, width: int) -> list[Line]:
        styles = self.component_styles()
        percent = f"{self.fraction:.0%}".rjust(4)
        words = " " + self.text(width - 1 - len(percent))
        bar = width - 1 - len(percent) - len(words)
        line: Line = []
        if bar >= MIN_BAR:
            full, half = divmod(round(self.fraction * bar * 2), 2)
            done = DONE * full + (HALF if half else "")
            line += [Segment(done, styles["progress--done"]),
                     Segment(DONE * (bar - len(done)), styles["progress--left"]),
                     Segment(" ")]
        line += [Segment(percent, styles["progress--percent"]),
                 Segment(words, styles["progress--text"])]
        return [line]


__all__ = ["ProgressLine"]
