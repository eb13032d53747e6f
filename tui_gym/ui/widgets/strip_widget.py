"""`StripWidget`: a widget that keeps its drawing (lines of segments, per key and width)
between frames and repaints only the lines that changed (a `render()` widget is drawn
afresh on every refresh, e.g. each focus change); `segments_of`, `panel_css` and friends."""

from __future__ import annotations

import re
from collections import OrderedDict
from collections.abc import Hashable, Iterable
from typing import Any, ClassVar

from rich.console import Console
from rich.segment import Segment
from rich.style import Style
from rich.text import Text
from textual import events
from textual.geometry import Region, Size
from textual.strip import Strip
from textual.widget import Widget

from tui_gym.ui.textual_internals import in_sight

Line = list[Segment]


def segments_of(text: Text, console: Console) -> list[Line]:
    """A Rich `Text` as lines of segments (no wrapping: one line per newline)."""
    lines: list[Line] = [[]]
    for segment in text.render(console, end=""):
        parts = segment.text.split("\n")
        for i, part in enumerate(parts):
            if i:
                lines.append([])
            if part:
                lines[-1].append(Segment(part, segment.style))
    return lines


def component_classes(css: str) -> set[str]:
    """The component classes a widget's CSS styles (its `.name--part` selectors)."""
    return set(re.findall(r"\.(\w+--[\w-]+)", css))


def panel_css(name: str, compact: bool = True) -> str:
    """The CSS of a bordered panel `name`, and (`compact`) none of its border or padding in
    the compact layout."""
    css = f"""
    {name} {{
        height: auto;
        border: round $primary-background-lighten-2;
        border-title-color: $text-muted;
        border-subtitle-color: $text-disabled;
        padding: 0 1;
    }}
    """
    return css + (f"Screen.compact {name} {{ border: none; padding: 0; }}\n" if compact else "")


def line_text(line: Iterable[Segment]) -> str:
    """The characters of a line of segments."""
    return "".join(segment.text for segment in line)


class StripWidget(Widget):
    """A widget drawn as cached lines of segments: a subclass says what its picture depends
    on (`picture_key()`) and draws it (`draw(width)`); `redraw()` asks for it again."""

    PICTURES: ClassVar[int] = 1  # how many (key, width) pictures to keep

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._version = 0
        self._pictures: OrderedDict[Hashable, list[Line]] = OrderedDict()
        self._strips: list[Strip] = []
        self._strips_of: tuple[int, Style, int] | None = None  # (id(lines), style, width)
        self._strips_lines: list[Line] | None = None  # keeps id(lines) valid
        self._laid_out: tuple[int, bool] | None = None  # (width, compact) at the last layout
        self._components: tuple[Style, dict[str, Style]] | None = None

    # --- what subclasses give ------------------------------------------------
    def picture_key(self) -> Hashable:
        """What the picture depends on, besides its width (`redraw()` changes it)."""
        return (self._version, self._compact(), self.rich_style)

    def draw(self, width: int) -> list[Line]:
        """The picture, `width` cells wide, as lines of segments."""
        raise NotImplementedError

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        return len(self.picture(width))

    # --- what owners call --------------------------------------------------
    def redraw(self, layout: bool = False) -> None:
        """The picture changed: draw it again on the next frame (only its changed lines,
        when the picture shown is there to compare with and `layout` is not asked)."""
        self._version += 1
        shown, width = self._strips_lines, self.content_size.width
        # Out of sight or shown at another width, it draws when Textual asks it to.
        if (layout or shown is None or not self.is_mounted
                or self._strips_of[2] != width or not in_sight(self)):  # type: ignore[index]
            self.refresh(layout=layout)
            return
        lines = self.picture(width)
        if len(lines) != len(shown):
            self.refresh()
            return
        changed = [y for y, (old, new) in enumerate(zip(shown, lines, strict=True))
                   if old != new]
        if changed:
            self.refresh(*(Region(0, y, width, 1) for y in changed))

    def picture(self, width: int) -> list[Line]:
        """The lines for `width` (drawn now unless kept from before)."""
        key = (self.picture_key(), width)
        lines = self._pictures.get(key)
        if lines is None:
            lines = self.draw(width)
            self._pictures[key] = lines
            while len(self._pictures) > self.PICTURES:
                self._pictures.popitem(last=False)
        else:
            self._pictures.move_to_end(key)
        return lines

    def render(self) -> Text:
        """The current picture as Rich text (Textual draws through `render_line`)."""
        lines = self.picture(self.content_size.width)
        return Text("\n").join(
            Text.assemble(*((s.text, s.style or "") for s in line)) for line in lines
        )

    def component_styles(self) -> dict[str, Style]:
        """Every component class's Rich style, kept while the widget's own style holds."""
        base = self.rich_style
        if self._components is None or self._components[0] != base:
            styles = {name: self.get_component_rich_style(name) for name in self.COMPONENT_CLASSES}
            self._components = (base, styles)
        return self._components[1]

    # --- size ------------------------------------------------------------------
    def _compact(self) -> bool:
        """Whether the app shows its compact layout (a class on the screen)."""
        return self.is_attached and self.screen.has_class("compact")

    def on_resize(self, event: events.Resize) -> None:
        # A new width, or the compact layout coming or going, may change the height
        # (an auto-height picture); a view shown again at its old size does not.
        shape = (event.size.width, self._compact())
        if shape != self._laid_out:
            self._laid_out = shape
            self.refresh(layout=True)

    # --- Textual's line API ----------------------------------------------------
    def render_lines(self, crop: Region) -> list[Strip]:
        width = self.content_size.width
        style = self.rich_style
        lines = self.picture(width)
        if self._strips_of != (id(lines), style, width) or self._strips_lines is not lines:
            combined: dict[Style | None, Style] = {}  # a picture uses a few styles, many times
            strips = []
            # A line as it was in the picture styled before keeps its strip (same style, width).
            before = self._strips_lines if self._strips_of is not None and \
                self._strips_of[1:] == (style, width) else None
            kept = self._strips
            for y, line in enumerate(lines):
                if before is not None and y < len(before) and y < len(kept) and before[y] == line:
                    strips.append(kept[y])
                    continue
                segments = []
                for segment in line:
                    own = segment.style
                    full = combined.get(own)
                    if full is None:
                        full = combined[own] = style + own
                    segments.append(Segment(segment.text, full))
                strips.append(Strip(segments).adjust_cell_length(width, style))
            self._strips = strips
            self._strips_of = (id(lines), style, width)
            self._strips_lines = lines
        return super().render_lines(crop)

    def render_line(self, y: int) -> Strip:
        if 0 <= y < len(self._strips):
            return self._strips[y]
        return Strip.blank(self.content_size.width, self.rich_style)


__all__ = ["Line", "StripWidget", "line_text", "panel_css", "segments_of"]
