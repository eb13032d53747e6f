"""A book figure's result as Rich renderables (its text escaped: data, never markup), for
`tui-gym book` and the Book view; heatmap panels as plain text grids, for `plan` and `book`."""

from __future__ import annotations

import textwrap

from rich.console import RenderableType
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from tui_gym.core.heatmap import Heatmap
from tui_gym.session.book.figure import FigureResult, heading
from tui_gym.terminal_chart import ChartSeries, band_chart

CHART_HEIGHT = 10


def figure_parts(result: FigureResult, width: int) -> list[RenderableType]:
    """The figure's title, charts (in `width` columns at most), claims and notes."""
    parts: list[RenderableType] = [f"[bold]{heading(result.figure)}[/]: {escape(result.title)}"]
    plot = max(20, min(100, width) - 14)
    for chart in result.charts:
        series = [ChartSeries(s.label, s.x, s.y, s.lo, s.hi) for s in chart.series]
        parts.append(band_chart(series, plot, CHART_HEIGHT, x_label=chart.x_label,
                                y_label=chart.title, skip_start=chart.skip_start))
    return parts


def claims_table(result: FigureResult) -> list[RenderableType]:
    """The book's claims beside the measured figures with their verdicts, then the notes."""
    checks = Table(title="The book's claims", title_justify="left")
    checks.add_column("claim")
    checks.add_column("book", justify="right")
    checks.add_column("measured", justify="right")
    checks.add_column("")
    for check in result.checks:
        verdict = "[green]✓ reproduced[/]" if check.ok else "[red]✗ differs[/]"
        checks.add_row(escape(check.claim), escape(str(check.book)), escape(str(check.measured)),
                       verdict)
    return [checks, *(Text(note, style="dim") for note in result.notes)]


def panel_text(panel: Heatmap, width: int = 80) -> Text:
    """The panel as its title, column labels, a row of right-aligned cell labels per row and
    its legend: compact enough for Jack's 21 x 21 grids on an 80-column terminal."""
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
