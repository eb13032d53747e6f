"""`TickBox`: a checkbox whose mark says its state: ✓ when ticked, blank when not.

Textual's own Checkbox draws the same "X" either way and tells the states
apart by colour alone, which is easy to misread (and lost in screenshots).
"""

from __future__ import annotations

from textual.widgets import Checkbox


class TickBox(Checkbox):
    """A Checkbox with a ✓ for on and an empty box for off."""

    @property
    def BUTTON_INNER(self) -> str:  # type: ignore[override]  # noqa: N802 - Textual's name
        return "✓" if self.value else " "
