"""The Book view mounted alone: a figure run from the list, drawn with its verdicts (anew
when the terminal narrows), and one stopped half-way."""

from __future__ import annotations

import io
import threading

import numpy as np
import pytest
from rich.console import Console
from textual.app import App, ComposeResult
from textual.widgets import Label, Static

from tests.waiting import wait_for
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    FigureStopped,
    Progress,
    Series,
)
from tui_gym.ui import book_view
from tui_gym.ui.book_view import BookView

started = threading.Event()


def _quick(options: FigureOptions, progress: Progress) -> FigureResult:
    progress(1, 2, "half")
    x = np.arange(1.0, 11.0)
    series = Series("learner", x, x, x - 1, x + 1)
    return FigureResult("9.1", "a quick figure", 3, (Chart("y", "episodes", (series,)),),
                        checks=(Check("it rises", "up", "up", True),
                                Check("it falls", "down", "up", False)))


def _endless(options: FigureOptions, progress: Progress) -> FigureResult:
    started.set()
    assert options.stop is not None
    options.stop.wait(30)
    raise FigureStopped("Figure 9.2 stopped")


FIGURES = [BookFigure("9.1", "A quick figure (Example 9.1): rising", "It rises.", "windy",
                      _quick, runs=3, episodes=10),
           BookFigure("9.2", "An endless figure", "It never ends.", "windy", _endless, runs=3,
                      episodes=10),
           BookFigure("9.3", "A figure over time steps", "Its runs count steps.", "windy",
                      _quick, runs=4)]


class BookHost(App[None]):
    def compose(self) -> ComposeResult:
        yield BookView(id="book")


@pytest.fixture(autouse=True)
def _figures(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(book_view, "figures", lambda: FIGURES)


def _text(app: App[None], selector: str) -> str:
    """What a Static shows, as plain text."""
    console = Console(width=100, record=True, file=io.StringIO())
    console.print(app.query_one(selector, Static).content)
    return console.export_text()


def _widest(app: App[None]) -> int:
    return max(len(line.rstrip()) for line in _text(app, "#book-figure").splitlines())


async def test_a_figure_runs_from_the_list_and_shows_its_verdicts() -> None:
    app = BookHost()
    async with app.run_test(size=(100, 40)) as pilot:
        view = app.query_one(BookView)
        view.focus_default()
        await pilot.pause()
        assert "It rises." in _text(app, "#book-about")
        await pilot.press("enter")
        await wait_for(pilot, lambda: not view.running, "the figure to finish")
        status = str(app.query_one("#book-status", Label).render())
        assert "1 of 2 claims reproduced" in status
        drawn = _text(app, "#book-figure")
        assert "it rises" in drawn and "✓ reproduced" in drawn and "✗ differs" in drawn
        # A narrower terminal draws the chart anew to fit.
        widest = max(len(line.rstrip()) for line in drawn.splitlines())
        await pilot.resize_terminal(70, 40)
        await wait_for(pilot, lambda: _widest(app) < widest - 20, "the chart to fit")


async def test_s_stops_a_figure_that_runs() -> None:
    started.clear()
    app = BookHost()
    async with app.run_test(size=(80, 24)) as pilot:
        view = app.query_one(BookView)
        view.focus_default()
        await pilot.press("down", "enter")
        await wait_for(pilot, started.is_set, "the figure to start")
        await pilot.press("enter")  # a second run waits for the first
        await pilot.press("s")
        await wait_for(pilot, lambda: not view.running, "the figure to stop")
        assert "Figure 9.2 stopped" in str(app.query_one("#book-status", Label).render())


async def test_a_figure_without_episodes_shows_its_runs_alone() -> None:
    app = BookHost()
    async with app.run_test(size=(80, 24)) as pilot:
        app.query_one(BookView).focus_default()
        await pilot.press("down", "down")
        await wait_for(pilot, lambda: "Its runs count steps." in _text(app, "#book-about"),
                       "the figure to be highlighted")
        about = _text(app, "#book-about")
        assert "4 runs · enter runs it" in about and "None" not in about
