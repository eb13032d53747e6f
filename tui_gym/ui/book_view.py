"""The Book view: Sutton & Barto's figures that run learners over seeds, run in the app."""

from __future__ import annotations

import threading
from typing import ClassVar

from rich.console import Group
from rich.markup import escape
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical, VerticalScroll
from textual.widgets import Label, OptionList, ProgressBar, Static
from textual.widgets.option_list import Option

from tui_gym.book_text import claims_table, figure_parts
from tui_gym.session.book import BookFigure, figures
from tui_gym.session.book.figure import FigureOptions, FigureResult, FigureStopped, heading
from tui_gym.ui.map_editing import SessionView

__all__ = ["BookView"]

FRAME_SECONDS = 0.1  # how often the view looks for news from the worker


class BookView(SessionView):
    """The book's run figures: pick one, run it, read its charts and verdicts."""

    SCOPED_CSS = False
    DEFAULT_CSS = """
    BookView #book-list { height: auto; max-height: 6;
                          border: round $primary-background-lighten-2; }
    BookView #book-list:focus { border: round $accent; }
    BookView #book-about { height: auto; color: $text-muted; }
    BookView #book-status-row { height: 1; }
    BookView #book-progress { width: 40; }
    BookView #book-status { padding: 0 1; color: $text-muted; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "stop", "Stop", tooltip="Stop the figure that runs"),
    ]

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self.figures: list[BookFigure] = [f for f in figures() if f.runs is not None]
        self._stop: threading.Event | None = None
        self._busy: BookFigure | None = None
        # Written by the worker thread, read by the timer: (done, total, what), the result.
        self._progress: tuple[int, int, str] | None = None
        self._outcome: FigureResult | str | None = None
        self.result: FigureResult | None = None  # the last figure drawn

    @staticmethod
    def key_help() -> list[tuple[str, str]]:
        return [("↑ / ↓", "pick a figure"),
                ("enter", "run it over seeds at its defaults (as `tui-gym book FIGURE`)"),
                ("s", "stop the figure that runs")]

    def compose(self) -> ComposeResult:
        yield OptionList(*(Option(f"{f.name}  {escape(f.title.split(' (')[0])}", id=f.name)
                           for f in self.figures), id="book-list")
        yield Static(id="book-about")
        with Vertical(id="book-status-row"):
            yield ProgressBar(id="book-progress", show_eta=False)
        yield Label("", id="book-status")
        with VerticalScroll(id="book-body"):
            yield Static(id="book-figure")

    def on_mount(self) -> None:
        self.query_one(OptionList).highlighted = 0
        self.set_interval(FRAME_SECONDS, self._tick)

    def on_unmount(self) -> None:
        if self._stop is not None:
            self._stop.set()

    def focus_default(self) -> None:
        for options in self.query(OptionList):  # none while it is being mounted
            options.focus()

    @property
    def running(self) -> bool:
        return self._busy is not None

    @on(OptionList.OptionHighlighted, "#book-list")
    def _highlighted(self, event: OptionList.OptionHighlighted) -> None:
        figure = self.figures[event.option_index]
        runs = f"{figure.runs} runs" + (f" × {figure.episodes} episodes"
                                        if figure.episodes is not None else "")
        self.query_one("#book-about", Static).update(
            f"[bold]{escape(figure.title)}[/]\n{escape(figure.about)}\n"
            f"[dim]{figure.world} · {runs} · enter runs it[/]")

    @on(OptionList.OptionSelected, "#book-list")
    def _selected(self, event: OptionList.OptionSelected) -> None:
        self.run_figure(self.figures[event.option_index])

    def run_figure(self, figure: BookFigure) -> None:
        """Run `figure` at its defaults on a worker thread (unless one runs already)."""
        if self._busy is not None:
            self.app.notify(f"{heading(self._busy.name)} is running: s stops it.")
            return
        self._busy, self._stop = figure, threading.Event()
        self._progress, self._outcome = (0, 1, "starting"), None
        self.query_one("#book-figure", Static).update("")
        self.result = None
        stop = self._stop
        self.run_worker(lambda: self._compute(figure, stop), thread=True, group="book",
                        exit_on_error=False)

    def _compute(self, figure: BookFigure, stop: threading.Event) -> None:
        """The worker: the figure's run, its progress and its result published."""

        def progress(done: int, total: int, what: str) -> None:
            self._progress = (done, total, what)

        try:
            self._outcome = figure.run(FigureOptions(stop=stop), progress)
        except FigureStopped:
            self._outcome = f"{heading(figure.name)} stopped."
        except Exception as exc:  # noqa: BLE001 - said in one line, the app goes on
            self._outcome = f"{heading(figure.name)} failed: {type(exc).__name__}: {exc}"

    def action_stop(self) -> None:
        if self._stop is not None and self._busy is not None:
            self._stop.set()
            self.query_one("#book-status", Label).update("stopping…")

    def _tick(self) -> None:
        figure = self._busy
        if figure is None:
            return
        outcome = self._outcome
        if outcome is None:
            if self._progress is not None:
                done, total, what = self._progress
                self.query_one(ProgressBar).update(total=max(total, 1), progress=done)
                self.query_one("#book-status", Label).update(escape(what))
            return
        self._busy = self._stop = None
        status = self.query_one("#book-status", Label)
        if isinstance(outcome, str):
            status.update(escape(outcome))
            return
        verdicts = sum(c.ok for c in outcome.checks)
        status.update(f"{heading(outcome.figure)}: {verdicts} of {len(outcome.checks)} claims "
                      "reproduced")
        self.query_one(ProgressBar).update(total=1, progress=1)
        self.result = outcome
        self._draw()

    def on_resize(self) -> None:
        self.call_after_refresh(self._draw)  # the charts fit the new width

    def _draw(self) -> None:
        result = self.result
        if result is None:
            return
        width = max(40, self.query_one("#book-body").size.width - 4)
        self.query_one("#book-figure", Static).update(
            Group(*figure_parts(result, width), *claims_table(result)))
