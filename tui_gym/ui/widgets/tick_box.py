"""`TickBox`: a checkbox marked ✓ when ticked and blank when not (not by colour alone)."""

from __future__ import annotations

from textual.widgets import Checkbox


class TickBox(Checkbox):
    """A Checkbox with a ✓ for on and an empty box for off."""

    @property
    def BUTTON_INNER(self) -> str:  # type: ignore[override]  # noqa: N802 - Textual's name
        return "✓" if self.value else " "
