"""`KeysInOrder`: an app mixin that handles the keys typed one after the other, in order
(Textual lets a key a widget takes overtake earlier keys still bubbling up)."""

from __future__ import annotations

import time
from collections import deque
from typing import Any

from textual import events
from textual.message_pump import MessagePump

__all__ = ["KEY_PATIENCE", "KeysInOrder"]

KEY_PATIENCE = 1.0  # seconds a key waits on the one before it, at most


class KeysInOrder:
    """Mixed into an `App` (before it): keys handled one at a time, in the order typed."""

    _key_under_way: events.Key | None = None
    _key_since = 0.0  # when the key under way was handed on
    _key_screen: Any = None  # the screen it was handed on in
    _keys_waiting: deque[events.Key] | None = None

    async def on_event(self, event: events.Event) -> None:
        if not isinstance(event, events.Key):
            await super().on_event(event)  # type: ignore[misc]
        elif event.is_forwarded:  # a key come back up to the app: its bindings now
            await super().on_event(event)  # type: ignore[misc]
            if event is self._key_under_way:
                self._done(event)
        elif self._key_under_way is None:
            await self._hand_on(event)
        else:
            if self._keys_waiting is None:
                self._keys_waiting = deque()
            self._keys_waiting.append(event)
            app: Any = self
            app.set_timer(KEY_PATIENCE, self._impatient)

    async def _hand_on(self, key: events.Key) -> None:
        """Handle `key` as Textual does; the next waiting key once it is done."""
        app: Any = self
        self._key_under_way, self._key_since = key, time.monotonic()
        self._key_screen = app.screen
        await super().on_event(key)  # type: ignore[misc]
        if not key.is_forwarded:  # a binding of the app's took it at once
            self._done(key)
            return
        target = app.focused or app.screen  # where Textual handed it
        self._follow(key, [node for node in target.ancestors_with_self if node is not app])

    def _follow(self, key: events.Key, path: list[MessagePump]) -> None:
        """Look again once the first of `path` (the widgets the key bubbles up through) has
        handled it, and so on up: once the last has, the key is done."""
        if key is not self._key_under_way:
            return
        if not path:
            self._done(key)
            return
        pump, rest = path[0], path[1:]
        if not pump.call_later(self._follow, key, rest):  # gone meanwhile: its parent
            self._follow(key, rest)

    def _done(self, key: events.Key) -> None:
        """`key` is handled: the next key goes now, or, when the key brought another
        screen, once that screen is drawn and has the focus."""
        if key is not self._key_under_way:
            return
        app: Any = self
        if app.screen is not self._key_screen:
            app.call_after_refresh(app.call_later, self._next_key, key)
        else:
            app.call_later(self._next_key, key)

    async def _impatient(self) -> None:
        key = self._key_under_way
        if key is not None and time.monotonic() - self._key_since >= KEY_PATIENCE:
            await self._next_key(key)

    async def _next_key(self, key: events.Key) -> None:
        if key is not self._key_under_way:
            return  # its turn is over already
        self._key_under_way = None
        waiting = self._keys_waiting
        if waiting:
            await self._hand_on(waiting.popleft())
