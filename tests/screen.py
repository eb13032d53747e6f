"""What a person sees: the app's current screen as plain text lines."""

from __future__ import annotations

import html
import re
from collections import defaultdict

_TEXT = re.compile(r'<text[^>]*\by="([\d.]+)"[^>]*>(.*?)</text>', re.S)


def screen_lines(app) -> list[str]:
    """The rendered screen, one string per terminal row (from Textual's own SVG export)."""
    svg = app.export_screenshot()
    rows: dict[float, list[str]] = defaultdict(list)
    for y, content in _TEXT.findall(svg):
        rows[float(y)].append(html.unescape(re.sub(r"<[^>]+>", "", content)))
    return ["".join(parts).replace("\xa0", " ") for _, parts in sorted(rows.items())]


def screen_text(app) -> str:
    """The whole screen as one string (rows joined by newlines)."""
    return "\n".join(screen_lines(app))


def drawn_text(app) -> str:
    """`screen_text` read from the strips Textual draws the screen with (the same render
    the SVG export starts from, without building the SVG)."""
    update = app.screen._compositor.render_update(full=True,
                                                  screen_stack=app._background_screens)
    rows = ("".join(segment.text for strip in row for segment in strip) for row in update.strips)
    return "\n".join(row.replace("\xa0", " ") for row in rows)
