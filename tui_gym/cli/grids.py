"""Heatmap panels as plain text grids, for `tui-gym plan` and `tui-gym book`.

`panel_text(panel)` writes a panel as its title, the column labels, a row of
cell labels per row (each right-aligned in a column as wide as the widest),
and its legend: compact enough for Jack's 21 x 21 grids on an 80-column terminal.
"""

from __future__ import annotations

import textwrap

from rich.text import Text

from tui_gym.core.heatmap import Heatmap

__all__ = ["panel_text"]


def panel_text(panel: Heatmap, width: int = 80) -> Text:
    """The panel as lines of text (see the module docstring)."""
    cells = [label for line in panel.labels for label in line] + [*panel.col_labels]
    cell = max((len(text) for text in cells), default=1) + 1
    head = max((len(text) for text in panel.row_labels), default=0)
    out = Text(panel.title + "\n", style="bold")
    out.append(" " * head + "".join(c.rjust(cell) for c in panel.col_labels) + "\n", "dim")
    for row_label, line in zip(panel.row_labels, panel.labels, strict=True):
        out.append(row_label.rjust(head), "dim")
        out.append("".join(label.rjust(cell) for label in line) + "\n")
    for wrapped in textwrap.wrap(panel.legend, max(20, width)):
        out.append(wrapped + "\n", "dim")
    return out
