"""Widgets drawn from kept lines: what they show, and when they draw again.

`StripWidget` keeps its picture between frames; these tests pin down that a
refresh that changes nothing draws nothing, that `redraw()` and a new width
do draw again, and that what reaches the screen is the picture. Then the
widgets built on it: the sparklines summarise their series, the stats table
lines its numbers up, and kept styles follow a theme change. (The key bar, a
strip widget too, follows the view in the app's own tests, test_ui_app.py.)
"""

from __future__ import annotations

from rich.segment import Segment
from textual.app import App, ComposeResult

from tui_gym.ui.textual_internals import in_sight
from tui_gym.ui.widgets.stats_panel import _grid
from tui_gym.ui.widgets.strip_widget import Line, StripWidget, line_text
from tui_gym.ui.widgets.training_charts import (
    BARS,
    TrainingCharts,
    bucket_means,
    sparkline_rows,
)

from .screen import screen_lines
from .waiting import wait_for


class Counter(StripWidget):
    """Draws `word` on every line and counts its drawings."""

    DEFAULT_CSS = "Counter { height: 3; }"

    def __init__(self) -> None:
        super().__init__()
        self.word = "alpha"
        self.draws = 0

    def draw(self, width: int) -> list[Line]:
        self.draws += 1
        return [[Segment(f"{self.word} {width}")] for _ in range(3)]


def drawn_lines(app: App[None], word: str) -> list[str]:
    """The screen's rows that start with `word`, without trailing blanks."""
    return [line.rstrip() for line in screen_lines(app) if line.startswith(word)]


class OneWidget(App[None]):
    def compose(self) -> ComposeResult:
        yield Counter()


async def test_a_strip_widget_draws_once_until_its_picture_changes() -> None:
    app = OneWidget()
    async with app.run_test(size=(40, 5)) as pilot:
        widget = app.query_one(Counter)
        await pilot.pause()
        assert drawn_lines(app, "alpha") == ["alpha 40"] * 3
        drawn = widget.draws
        assert drawn == 1

        widget.refresh()  # what a focus change or a view switch does
        await pilot.pause()
        assert widget.draws == drawn, "a plain refresh drew the same picture again"

        widget.word = "beta"
        widget.redraw()
        await pilot.pause()
        assert widget.draws == drawn + 1
        assert drawn_lines(app, "beta") == ["beta 40"] * 3

        await pilot.resize_terminal(30, 5)
        await pilot.pause()
        assert drawn_lines(app, "beta") == ["beta 30"] * 3, "a new width is a new picture"


class Rows(StripWidget):
    """Draws its `rows`, and notes which lines Textual asks it for."""

    DEFAULT_CSS = "Rows { height: auto; }"

    def __init__(self) -> None:
        super().__init__()
        self.rows = ["one", "two", "three"]
        self.asked: list[int] = []

    def draw(self, width: int) -> list[Line]:
        return [[Segment(row)] for row in self.rows]

    def get_content_height(self, container: object, viewport: object, width: int) -> int:
        return len(self.rows)

    def render_line(self, y: int):  # type: ignore[no-untyped-def]
        self.asked.append(y)
        return super().render_line(y)


class OneRows(App[None]):
    def compose(self) -> ComposeResult:
        yield Rows()


def rows_shown(app: App[None]) -> list[str]:
    """The screen's rows that are not blank, without trailing blanks (the screenshot's
    title left out)."""
    return [line.rstrip() for line in screen_lines(app) if line.strip() not in ("", app.title)]


async def test_a_redraw_repaints_only_the_lines_that_changed() -> None:
    app = OneRows()
    async with app.run_test(size=(20, 6)) as pilot:
        widget = app.query_one(Rows)
        await pilot.pause()
        assert set(widget.asked) == {0, 1, 2}
        assert in_sight(widget)

        widget.asked.clear()
        widget.rows = ["one", "TWO", "three"]
        widget.redraw()
        await pilot.pause()
        assert widget.asked == [1], "lines that did not change were drawn again"
        assert rows_shown(app) == ["one", "TWO", "three"]

        widget.asked.clear()
        widget.redraw()  # the same picture: nothing to repaint
        await pilot.pause()
        assert widget.asked == []

        widget.rows = ["one", "two", "three", "four"]  # a new height: all of it again
        widget.redraw(layout=True)
        await pilot.pause()
        assert rows_shown(app) == ["one", "two", "three", "four"]

        widget.display = False  # hidden, a redraw waits for the widget to show again
        await pilot.pause()
        widget.rows = ["uno", "two", "three", "four"]
        widget.redraw()
        widget.display = True
        await pilot.pause()
        assert rows_shown(app) == ["uno", "two", "three", "four"]


async def test_a_strip_widget_pads_and_crops_to_its_width() -> None:
    app = OneWidget()
    async with app.run_test(size=(6, 5)) as pilot:
        await pilot.pause()
        assert drawn_lines(app, "alpha") == ["alpha"] * 3  # "alpha 6" cropped to 6 cells


def test_bucket_means_average_each_bucket_and_sample_short_series() -> None:
    assert bucket_means([1, 3, 5, 7], 2) == [2.0, 6.0]
    assert bucket_means(list(range(10)), 3) == [1.0, 4.0, 7.5]  # buckets of 3, 3, 4
    assert bucket_means([4.0, 8.0], 4) == [4.0, 4.0, 8.0, 8.0]
    assert bucket_means([], 5) == []


def test_a_sparkline_rises_with_its_data() -> None:
    from rich.color import Color

    low, high = Color.from_rgb(0, 0, 0), Color.from_rgb(255, 255, 255)
    rows = sparkline_rows([0, 1, 2, 3, 4, 5, 6, 7], 8, 2, low, high)
    assert len(rows) == 2 and all(len(line_text(r)) == 8 for r in rows)
    top, bottom = line_text(rows[0]), line_text(rows[1])

    def height(col: int) -> int:  # eighths filled in a column, 0..16
        cell = lambda ch: 0 if ch == " " else 8 if ch == "█" else BARS.index(ch) + 1  # noqa: E731
        return cell(bottom[col]) + cell(top[col])

    heights = [height(c) for c in range(8)]
    assert heights == sorted(heights) and heights[0] < heights[-1]
    assert top[-1] == "█" and bottom[-1] == "█"  # the highest value fills both rows
    assert top[0] == " "  # the lowest value stays in the bottom row
    # the high end takes the high colour, the low end the low one
    assert rows[1][-1].style.color.get_truecolor() == (255, 255, 255)
    assert rows[1][0].style.color.get_truecolor() == (0, 0, 0)


def test_a_flat_or_empty_sparkline_is_a_level_line() -> None:
    from rich.color import Color

    c = Color.from_rgb(9, 9, 9)
    flat = [line_text(r) for r in sparkline_rows([2.0] * 5, 5, 2, c, c)]
    assert len(set(flat[0])) == 1 and len(set(flat[1])) == 1  # every column alike
    empty = [line_text(r) for r in sparkline_rows([], 4, 2, c, c)]
    assert empty == ["    ", "▁▁▁▁"]


def test_the_stats_grid_lines_up_its_columns() -> None:
    rows = [
        [("episodes", "dim"), ("60,000", "bold"), ("steps", "dim"), ("85,356", "")],
        [("eps/s", "dim"), ("50,000", ""), ("time", "dim"), ("0:01", "")],
    ]
    lines = [line_text(line) for line in _grid(rows, 40)]
    assert [len(text) for text in lines] == [40, 40]
    first, second = lines
    assert first.startswith("episodes") and second.startswith("eps/s")
    # the values end in the same columns: right-aligned in their halves
    assert first.index("60,000") + 6 == second.index("50,000") + 6
    assert first.endswith("85,356") and second.endswith("0:01")
    assert first.index("steps") == second.index("time")



def test_heatmap_cells_take_their_colour_from_their_place_on_the_scale() -> None:
    import numpy as np

    from tui_gym.ui.widgets.heatmap_view import (
        COLOUR_STEPS,
        DIVERGING,
        SEQUENTIAL,
        ColourScale,
        _cell_style,
        _hex,
    )

    top = COLOUR_STEPS - 1
    diverging = ColourScale(-0.5, 1.0)  # both signs: symmetric around zero
    steps = diverging.steps(np.array([-1.0, 0.0, 1.0, np.nan, 2.0]))
    assert steps.tolist() == [0, round(top / 2), top, -1, top]  # clipped at the ends
    sequential = ColourScale(0.2, 0.6)
    assert sequential.steps(np.array([0.2, 0.4, 0.6])).tolist() == [0, round(top / 2), top]
    flat = ColourScale(0.3, 0.3)
    assert flat.steps(np.array([0.3])).tolist() == [round(top / 2)]

    assert _cell_style(True, 0, False).bgcolor.name == _hex(DIVERGING[0])
    assert _cell_style(True, top, False).bgcolor.name == _hex(DIVERGING[-1])
    assert _cell_style(False, top, False).bgcolor.name == _hex(SEQUENTIAL[-1])
    assert _cell_style(False, 5, True).bold and _cell_style(False, 5, True).underline
    assert _cell_style(False, -1, False).bgcolor is None  # no value: no colour


class OneChart(App[None]):
    def compose(self) -> ComposeResult:
        yield TrainingCharts()


async def test_kept_component_styles_follow_a_theme_change() -> None:
    app = OneChart()
    async with app.run_test(size=(80, 12)) as pilot:
        await pilot.pause()
        charts = app.query_one(TrainingCharts)
        name = "charts--return-high"
        before = charts.component_styles()[name]
        assert before == charts.get_component_rich_style(name)
        app.theme = "textual-light"
        await pilot.pause()
        after = charts.component_styles()[name]
        assert after == charts.get_component_rich_style(name)
        assert after != before, "the light theme's colours never reached the charts"


class OneProgress(App[None]):
    def compose(self) -> ComposeResult:
        from tui_gym.ui.widgets.progress_line import ProgressLine

        yield ProgressLine()


async def test_the_progress_line_fills_toward_the_budget() -> None:
    from tui_gym.ui.widgets.progress_line import DONE, HALF, ProgressLine

    app = OneProgress()
    async with app.run_test(size=(60, 3)) as pilot:
        line = app.query_one(ProgressLine)
        line.show(30_000, 200_000, eta="0:04")
        await pilot.pause()
        text = line.render().plain
        assert text.endswith(" 15% 30,000 / 200,000 episodes · eta 0:04")
        assert len(text) == 60
        bar = text.split(" ")[0]
        assert set(bar) <= {DONE, HALF} and len(bar) == 60 - len(" 15% 30,000 / 200,000 "
                                                               "episodes · eta 0:04") - 1
        done = line.render().spans[0]  # the done part has a colour of its own
        assert done.end - done.start == -(-round(0.15 * len(bar) * 2) // 2)  # halves round up
        line.show(200_000, 200_000)
        await pilot.pause()
        assert line.render().plain.endswith("100% 200,000 / 200,000 episodes")
        await pilot.resize_terminal(20, 3)
        await wait_for(pilot, lambda: line.size.width == 20, "the line laid out 20 wide")
        assert DONE not in line.render().plain  # too narrow for a bar: the numbers only
