"""`FiguresTable`: the final figures of the runs compared, with their 95% intervals."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

from rich.segment import Segment
from rich.style import Style

from tui_gym.core.experiments import Figure
from tui_gym.ui.compare_series import FigureRow
from tui_gym.ui.widgets.compare_chart import colour
from tui_gym.ui.widgets.numbers import compact_count, cut
from tui_gym.ui.widgets.strip_widget import Line, StripWidget

MISSING = "–"


def with_interval(figure: Figure | None) -> str:
    """'+0.123 ± 0.045', or '+0.123' without an interval, or '–'."""
    if figure is None or figure.value != figure.value:  # NaN: no value
        return MISSING
    text = f"{figure.value:+.3f}"
    if figure.ci95 is not None:
        text += f" ± {figure.ci95:.3f}"
    return text


def plain(figure: Figure | None, sign: bool = True) -> str:
    if figure is None or figure.value != figure.value:
        return MISSING
    return f"{figure.value:+.4f}" if sign else f"{figure.value:.4f}"


# (header, how a row reads, dropped in this order when short of room: lower goes first)
COLUMNS: tuple[tuple[str, str, int], ...] = (
    ("Seeds", "seeds", 3),
    ("Episodes", "episodes", 1),
    ("Return, last 10%", "return", 9),
    ("Exact value", "exact", 2),
    ("Gap", "gap", 4),
    ("Status", "note", 5),  # only when a row has one (running, interrupted, failed)
)
MIN_LABEL = 10


def cells(row: FigureRow) -> dict[str, str]:
    """A row's figures as the table writes them."""
    return {
        "seeds": f"{row.seeds:,}",
        "episodes": MISSING if row.episodes is None else compact_count(row.episodes),
        "return": with_interval(row.mean_return_last), "exact": plain(row.exact_value),
        "gap": plain(row.exact_gap, sign=False), "note": row.note,
    }


def layout(rows: Sequence[FigureRow], width: int) -> list[tuple[str, str, int]]:
    """The columns that fit `width`, each (header, key, width)."""
    texts = [cells(row) for row in rows]
    columns = [
        (header, key, max(len(header), *(len(t[key]) for t in texts)), rank)
        for header, key, rank in COLUMNS
        if key != "note" or any(t["note"] for t in texts)
    ]
    def too_wide() -> bool:
        return MIN_LABEL + 2 + sum(w + 2 for _, _, w, _ in columns) > width

    # Short of room, a column no run has a figure in goes first (a game without a model).
    for column in [c for c in columns if all(t[c[1]] == MISSING for t in texts)]:
        if too_wide():
            columns.remove(column)
    while columns and too_wide():
        columns.remove(min(columns, key=lambda c: c[3]))
    return [(header, key, w) for header, key, w, _ in columns]


class FiguresTable(StripWidget):
    """A row of final figures per run (`show(rows, colours)`)."""

    COMPONENT_CLASSES: ClassVar[set[str]] = {"figures--header", "figures--note"}
    DEFAULT_CSS = """
    FiguresTable { height: auto; padding: 0 1; }
    FiguresTable > .figures--header { color: $text-muted; text-style: bold; }
    FiguresTable > .figures--note { color: $text-warning; }
    """

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.rows: tuple[FigureRow, ...] = ()
        self._colours: tuple[int, ...] = ()

    def show(self, rows: Sequence[FigureRow], colours: Sequence[int] | None = None) -> None:
        rows = tuple(rows)
        colours = tuple(colours) if colours is not None else tuple(range(len(rows)))
        if rows != self.rows or colours != self._colours:
            self.rows, self._colours = rows, colours
            self.redraw(layout=True)

    def draw(self, width: int) -> list[Line]:
        if not self.rows:
            return []
        styles = self.component_styles()
        header_style, note_style = styles["figures--header"], styles["figures--note"]
        columns = layout(self.rows, width)
        label_width = max(MIN_LABEL, width - 2 - sum(w + 2 for _, _, w in columns))
        head: Line = [Segment("  " + "Run".ljust(label_width), header_style)]
        for header, key, w in columns:
            text = header.ljust(w) if key == "note" else header.rjust(w)
            head.append(Segment("  " + text, header_style))
        lines = [head]
        for row, place in zip(self.rows, self._colours, strict=True):
            texts = cells(row)
            line: Line = [
                Segment("▍ ", Style(color=colour(place))),
                Segment(cut(row.label, label_width).ljust(label_width)),
            ]
            for _header, key, w in columns:
                if key == "note":
                    line.append(Segment("  " + texts[key].ljust(w), note_style))
                else:
                    line.append(Segment("  " + texts[key].rjust(w)))
            lines.append(line)
        return lines


__all__ = ["FiguresTable", "cells", "layout", "plain", "with_interval"]
