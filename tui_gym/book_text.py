"""A book figure's result as Rich renderables, for `tui-gym book` and the app's Book view.

`figure_parts(result, width)`: its title, each chart as a band chart (the
charts of `compare`), the table of the book's claims with their verdicts, and
its notes. Text from the figure is escaped: it is data, never markup.
"""

from __future__ import annotations

from rich.console import RenderableType
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from tui_gym.session.book.figure import FigureResult, heading
from tui_gym.terminal_chart import ChartSeries, band_chart

__all__ = ["CHART_HEIGHT", "claims_table", "figure_parts"]

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
