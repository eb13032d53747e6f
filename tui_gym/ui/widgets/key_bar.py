"""`KeyBar`: the live key bindings along the bottom, drawn as one line of text."""

from __future__ import annotations

from collections.abc import Hashable
from itertools import groupby

from rich.cells import cell_len
from rich.text import Text
from textual import events
from textual.binding import Binding
from textual.screen import Screen

from tui_gym.ui.widgets.strip_widget import Line, StripWidget, segments_of

HELP_KEYS = frozenset({"question_mark,f1", "question_mark", "f1"})  # kept when keys are left out


class KeyBar(StripWidget):
    """One line listing the active key bindings; click a key to press it."""

    PICTURES = 6

    COMPONENT_CLASSES = {"keybar--key"}
    DEFAULT_CSS = """
    KeyBar { dock: bottom; height: 1; background: $footer-background; color: $footer-foreground; }
    KeyBar > .keybar--key {
        color: $footer-key-foreground;
        background: $footer-key-background;
        text-style: bold;
    }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self._entries: list[tuple[str, str, bool, str]] = []  # (keys shown, text, enabled, key)
        self._palette: tuple[str, str] | None = None

    def on_mount(self) -> None:
        self.screen.bindings_updated_signal.subscribe(self, self._bindings_changed)
        self._bindings_changed(self.screen)

    def _bindings_changed(self, screen: Screen) -> None:
        if not self.is_attached or screen is not self.screen:
            return
        active = screen.active_bindings
        shown: list[tuple[Binding, bool]] = []
        seen_actions: set[str] = set()
        for _node, binding, enabled, _tooltip in active.values():
            if binding.show and binding.action not in seen_actions:
                seen_actions.add(binding.action)
                shown.append((binding, enabled))
        entries: list[tuple[str, str, bool, str]] = []
        app = self.app
        for group, items in groupby(shown, lambda item: item[0].group):
            members = list(items)
            if group is not None and len(members) > 1:
                keys = " ".join(app.get_key_display(b) for b, _ in members)
                entries.append((keys, group.description, any(e for _, e in members),
                                members[0][0].key))
            else:
                for binding, enabled in members:
                    entries.append((app.get_key_display(binding), binding.description, enabled,
                                    binding.key))
        palette = None
        if app.ENABLE_COMMAND_PALETTE:
            found = active.get(app.COMMAND_PALETTE_BINDING)
            if found is not None:
                palette = (app.get_key_display(found.binding), found.binding.description)
        if entries != self._entries or palette != self._palette:
            self._entries, self._palette = entries, palette
            self.refresh()

    def picture_key(self) -> Hashable:
        key_style = self.get_component_rich_style("keybar--key", partial=True)
        return (tuple(self._entries), self._palette, key_style)

    def draw(self, width: int) -> list[Line]:
        text, _spans = self._line(width)
        return segments_of(text, self.app.console)[:1]

    def _fitting(self, room: int) -> tuple[list[tuple[str, str, bool, str]], bool]:
        """The entries that fit whole in `room` cells, and whether some were left out
        (then one cell is kept for the "…")."""
        entries = list(self._entries)

        def width(entry: tuple[str, str, bool, str]) -> int:
            keys, description = entry[0], entry[1]
            return cell_len(f" {keys} ") + (cell_len(description) + 1 if description else 0)

        if sum(width(e) for e in entries) <= room:
            return entries, False
        while entries and sum(width(e) for e in entries) > room - 1:
            last = next((i for i in range(len(entries) - 1, -1, -1)
                         if entries[i][3] not in HELP_KEYS), None)
            entries.pop(len(entries) - 1 if last is None else last)
        return entries, True

    def _line(self, width: int) -> tuple[Text, list[tuple[int, int, str]]]:
        """The line and the (start, end, key) of each key on it, for clicks."""
        key_style = self.get_component_rich_style("keybar--key", partial=True)
        text = Text(no_wrap=True, overflow="crop", end="")
        spans: list[tuple[int, int, str]] = []
        palette = self._palette if width else None
        tail = f"▏{palette[0]} {palette[1]} " if palette else ""
        room = max(0, width - cell_len(tail))
        entries, more = self._fitting(room)
        for keys, description, enabled, key in entries:
            start = text.cell_len
            text.append(f" {keys} ", style=key_style)
            text.append(f"{description} " if description else "", style="" if enabled else "dim")
            if not enabled:
                text.stylize("dim", start)
            spans.append((start, text.cell_len, key))
        if more:
            text.append("…", style="dim")
        if palette:
            keys, description = palette
            text.append(" " * max(0, room - text.cell_len))
            text.append(tail[0], style="dim")
            text.append(f"{keys} ", style=key_style)
            text.append(description + " ")
            spans.append((room, width, "ctrl+p"))
        return text, spans

    def on_click(self, event: events.Click) -> None:
        _text, spans = self._line(self.size.width)
        for start, end, key in spans:
            if start <= event.x < end:
                event.stop()
                self.app.simulate_key(key)
                return
