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
