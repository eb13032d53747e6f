"""`TextField`: Textual's `Input`, with its editing keys handled in the field itself."""

from __future__ import annotations

from textual import events
from textual.binding import Binding
from textual.widgets import Input

__all__ = ["TextField"]

_EDITING_KEYS = {binding.key: binding.action for binding in Binding.make_bindings(Input.BINDINGS)}


class TextField(Input):
    """An `Input` that handles its editing keys where it has the focus."""

    async def on_key(self, event: events.Key) -> None:
        action = _EDITING_KEYS.get(event.key)
        if action is None or event.is_printable:
            return
        event.stop()
        event.prevent_default()
        await self.run_action(action)
