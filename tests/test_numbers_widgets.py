"""The Train view's numbers, widget by widget, mounted alone: what a person reads.

The stats table never cuts a number and says "–" where nothing stands behind a
figure; its badge says "finished" only for a used-up budget; a sparkline's
"max" and "min" are those of the columns it draws, the value beside it among
them, and a curve whose range rounds away is drawn flat; the progress line
shortens large counts instead of cutting them.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from textual.app import App, ComposeResult

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.engine.trainer import SERIES_NAMES
from tui_gym.games.base import ReferenceMetrics, Scope
from tui_gym.ui.widgets.numbers import compact_count, fit, number_forms
from tui_gym.ui.widgets.progress_line import ProgressLine
from tui_gym.ui.widgets.stats_panel import StatsPanel, run_state
from tui_gym.ui.widgets.training_charts import (
    MIN_SPARK,
    NAME_WIDTH,
    RANGE_WIDTH,
    VALUE_WIDTH,
    TrainingCharts,
)


def drawn(widget) -> list[str]:
    """The widget's lines as it draws them; none may be wider than its content."""
    lines = widget.render().plain.split("\n")
    width = widget.content_size.width
    assert all(len(line) <= width for line in lines), (width, lines)  # nothing cropped
    return lines


def snapshot(**changes) -> TrainingSnapshot:
    fields = dict(
        engine="model", episodes=0, steps=0, seconds=0.0, episodes_per_second=0.0,
        epsilon=1.0, mean_return=0.0, mean_length=0.0, mean_abs_td=0.0, window=1000,
        series={name: () for name in SERIES_NAMES}, q=np.zeros((1, 2)), keys=None,
        budget=100, recorded=0,
    )
    fields.update(changes)
    return TrainingSnapshot(**fields)


class Alone(App[None]):
    def __init__(self, widget) -> None:
        super().__init__()
        self.widget = widget

    def compose(self) -> ComposeResult:
        yield self.widget


def test_the_badge_says_finished_only_for_a_used_up_budget() -> None:
    assert run_state(True, 0, 0, 100) == "running"
    assert run_state(False, 100, 900, 100) == "finished"
    assert run_state(False, 120, 900, 100) == "finished"  # the budget was lowered below
    assert run_state(False, 100, 900, 500) == "paused"  # ... or raised above the count
    assert run_state(False, 0, 7, 100) == "paused"  # paused before the first episode ends
    assert run_state(False, 0, 0, 100) == "idle"  # after a reset, never "finished"
    assert run_state(False, 0, 0, 1) == "idle"


def row_values(text: str) -> dict[str, str]:
    """'name value' pairs as the stats table shows them (names of one word or |TD|)."""
    return dict(re.findall(r"(episodes|steps|eps/s|time|epsilon|return|length|\|TD\|)"
                           r" +(\S+)", text))


@pytest.mark.parametrize("width", [80, 34, 24])
async def test_large_numbers_are_shortened_never_cut(width: int) -> None:
    panel = StatsPanel()
    app = Alone(panel)
    async with app.run_test(size=(width, 16)) as pilot:
        panel.show_snapshot(snapshot(
            episodes=123_456_789, steps=5_496_812_345, seconds=4000.0,
            episodes_per_second=1_581_007.0, epsilon=0.05, mean_return=-1234.56789,
            mean_length=1.53, mean_abs_td=0.61, recorded=1000, budget=200_000_000,
        ))
        panel.show_reference(ReferenceMetrics({"exact_value": -48_400.123, "gap": 0.0019},
                                              "", Scope(True, "exact with ScaleReward")))
        await pilot.pause()
        text = "\n".join(drawn(panel))
        values = row_values(text)
        assert values["episodes"] in ("123,456,789", "123M")
        assert values["steps"] in ("5,496,812,345", "5.50B")
        assert values["eps/s"] in ("1,581,007", "1.58M")
        assert values["time"] == "1:06:40"
        assert values["return"] in ("-1234.5679", "-1235", "-1.23e+03")
        assert "exact with ScaleReward" in " ".join(text.split())  # wrapped, at narrow widths
        assert re.search(r"exact value +(-48400\.1230|-4\.84e\+04|-4\.8e\+04|-4\.840e\+04)", text)
        if width == 80:  # room for every figure in full
            assert "5,496,812,345" in text and "123,456,789" in text


async def test_figures_with_no_data_read_as_a_dash() -> None:
    panel = StatsPanel()
    app = Alone(panel)
    async with app.run_test(size=(70, 12)) as pilot:
        # A saved agent just loaded: its counts, but no episode in the statistics.
        panel.show_snapshot(snapshot(episodes=50_000, steps=75_000, epsilon=0.05))
        await pilot.pause()
        values = row_values("\n".join(drawn(panel)))
        assert values["episodes"] == "50,000" and values["steps"] == "75,000"
        assert values["epsilon"] == "0.050"
        for name in ("eps/s", "time", "return", "length", "|TD|"):
            assert values[name] == "–", name
        assert "last" not in str(panel.border_subtitle)  # no rolling window of nothing


def chart_ends(charts: TrainingCharts, name: str) -> tuple[str, str, str]:
    """(value, max, min) beside the sparkline called `name`."""
    lines = drawn(charts)
    row = next(i for i, line in enumerate(lines) if name in line)
    value = lines[row].split(name, 1)[1].split()[0]
    top = re.search(r"max (\S+)", lines[row]).group(1)
    bottom = re.search(r"min (\S+)", lines[row + 1]).group(1)
    return value, top, bottom


async def test_sparkline_ranges_are_those_of_what_is_drawn() -> None:
    charts = TrainingCharts()
    app = Alone(charts)
    width = 100
    async with app.run_test(size=(width, 12)) as pilot:
        td = tuple(np.linspace(0.9, 0.5965, 300))  # the current value lies below the series
        eps = tuple(np.linspace(1.0, 0.421, 300))  # then the budget went up: epsilon rose
        charts.update_from(snapshot(
            episodes=3000, recorded=3000, mean_abs_td=0.5893, epsilon=0.679,
            series={"return": (0.1,) * 300, "length": (2.0,) * 300, "td_error": td,
                    "epsilon": eps},
        ))
        await pilot.pause()
        spark = charts.content_size.width - NAME_WIDTH - VALUE_WIDTH - 2 - RANGE_WIDTH - 1
        for key, name, fmt in (("td_error", "mean |TD|", "{:.4f}"),
                               ("epsilon", "epsilon", "{:.3f}")):
            columns = charts.plotted(key, spark)
            value, top, bottom = chart_ends(charts, name)
            assert top == fmt.format(max(columns)) and bottom == fmt.format(min(columns))
            assert float(bottom) <= float(value) <= float(top), (name, value, top, bottom)
            assert columns[-1] == float(value)  # the curve ends at the value beside it
        assert chart_ends(charts, "mean |TD|")[2] == "0.5893"
        value, top, bottom = chart_ends(charts, "epsilon")
        assert float(bottom) < float(value) < float(top)  # 0.679, within the run's range


async def test_a_narrow_box_keeps_its_curves_and_drops_the_ranges() -> None:
    charts = TrainingCharts()
    app = Alone(charts)
    async with app.run_test(size=(40, 12)) as pilot:  # the Train view's, the board beside
        charts.update_from(snapshot(
            episodes=300, recorded=300, mean_return=0.5, mean_length=9.0, mean_abs_td=0.1,
            epsilon=0.9, series={"return": tuple(np.linspace(-1, 0.5, 50)),
                                 "length": tuple(np.linspace(30, 9, 50)),
                                 "td_error": (0.1,) * 50, "epsilon": (0.9,) * 50},
        ))
        await pilot.pause()
        lines = drawn(charts)
        assert not any("max" in line or "min" in line for line in lines), lines
        row = next(i for i, line in enumerate(lines) if "mean return" in line)
        bars = re.sub(r"[^▁▂▃▄▅▆▇█]", "", lines[row + 1])  # the lower row: every column
        assert len(bars) >= MIN_SPARK and len(set(bars)) > 2, lines  # a rising curve


async def test_a_flat_series_is_drawn_flat() -> None:
    charts = TrainingCharts()
    app = Alone(charts)
    async with app.run_test(size=(90, 12)) as pilot:
        # Rolling means of a constant carry rounding noise: the range rounds to one number.
        noisy = tuple(0.05 + e for e in np.random.default_rng(0).normal(0, 1e-17, 200))
        charts.update_from(snapshot(
            episodes=2000, recorded=2000, epsilon=0.05, mean_return=1.0, mean_length=3.0,
            mean_abs_td=0.01,
            series={"return": (1.0,) * 200, "length": tuple(np.linspace(9, 3, 200)),
                    "td_error": (0.01,) * 200, "epsilon": noisy},
        ))
        await pilot.pause()
        lines = drawn(charts)
        for name in ("epsilon", "mean return"):
            row = next(i for i, line in enumerate(lines) if name in line)
            bars = [set(re.sub(r"[^▁▂▃▄▅▆▇█]", "", lines[r])) for r in (row, row + 1)]
            assert all(len(b) <= 1 for b in bars), (name, bars)  # one glyph a row: level
            _, top, bottom = chart_ends(charts, name)
            assert top == bottom
        row = next(i for i, line in enumerate(lines) if "ep. length" in line)
        assert len(set(re.sub(r"[^▁▂▃▄▅▆▇█]", "", lines[row + 1]))) > 2  # a slope is a slope


async def test_chart_values_are_shortened_never_cut() -> None:
    charts = TrainingCharts()
    app = Alone(charts)
    async with app.run_test(size=(90, 12)) as pilot:
        charts.update_from(snapshot(
            episodes=10, recorded=10, mean_return=-1_234_567.0, mean_length=123_456.0,
            series={"return": (-1_234_567.0, -2_000_000.0), "length": (1.0, 123_456.0),
                    "td_error": (0.5, 0.4), "epsilon": (1.0, 0.9)},
        ))
        await pilot.pause()
        value, top, bottom = chart_ends(charts, "mean return")
        assert float(value) == pytest.approx(-1_234_567.0, rel=5e-3)
        assert float(bottom) == pytest.approx(-2_000_000.0, rel=5e-3)
        value, top, _ = chart_ends(charts, "ep. length")
        assert float(value) == pytest.approx(123_456.0, rel=5e-3) == float(top)


async def test_charts_of_no_episodes_read_as_a_dash() -> None:
    charts = TrainingCharts()
    app = Alone(charts)
    async with app.run_test(size=(90, 12)) as pilot:
        charts.update_from(snapshot(episodes=50_000, epsilon=0.05))  # just loaded
        await pilot.pause()
        text = "\n".join(drawn(charts))
        for name in ("mean return", "ep. length", "mean |TD|"):
            assert chart_ends_value(text, name) == "–"
        assert chart_ends_value(text, "epsilon") == "0.050"  # known, as the stats say
        assert "max" not in text and "rolling mean" not in str(charts.border_subtitle)


def chart_ends_value(text: str, name: str) -> str:
    line = next(line for line in text.splitlines() if name in line)
    return line.split(name, 1)[1].split()[0]


@pytest.mark.parametrize("width", [70, 36, 26])
async def test_the_progress_line_never_cuts_its_counts(width: int) -> None:
    line = ProgressLine()
    app = Alone(line)
    async with app.run_test(size=(width, 3)) as pilot:
        line.show(617_283_945, 1_000_000_000, eta="1:23:45")
        await pilot.pause()
        text = drawn(line)[0].rstrip()
        assert ("617,283,945 / 1,000,000,000" in text) or ("617M / 1.00B" in text)
        assert text.endswith("· eta 1:23:45") == (width >= 36)  # the time left goes first


def test_compact_forms_keep_their_value() -> None:
    assert [compact_count(n) for n in (9_999, 12_345, 999_700, 5_496_812, 1_234_567_890)] == [
        "9,999", "12.3k", "1.00M", "5.50M", "1.23B"]
    forms = number_forms(1234567.0, "+.3f")
    assert fit(forms, 9) == "+1.23e+06" and fit(forms, 20) == "+1234567.000"


async def test_a_new_snapshot_repaints_the_figures_that_changed_not_the_border() -> None:
    panel = StatsPanel()
    app = Alone(panel)
    asked: list[int] = []
    line_of = panel.render_line
    panel.render_line = lambda y: asked.append(y) or line_of(y)  # type: ignore[method-assign]
    async with app.run_test(size=(60, 14)) as pilot:
        panel.show_state("running")
        panel.show_snapshot(snapshot(episodes=1_000, steps=1_500, recorded=1_000))
        await pilot.pause()
        asked.clear()
        panel.show_snapshot(snapshot(episodes=2_000, steps=1_500, recorded=1_000))
        await pilot.pause()
        assert len(set(asked)) == 1, "more than the line of the episode count was drawn again"
        assert row_values(panel.plain)["episodes"] == "2,000"
        assert "running" in str(panel.border_title)
