"""Textual's private names, each with a fallback: the app runs with every fallback forced
(`TUI_GYM_STOCK_TEXTUAL=all`), and each part falls back on its own when a name it needs
is missing or has changed shape."""

from __future__ import annotations

import asyncio
import threading
from pathlib import Path

import pytest
import textual._wait
from rich.segment import Segment
from textual.app import App, ComposeResult
from textual.drivers.headless_driver import HeadlessDriver
from textual.message import Message
from textual.screen import Screen
from textual.strip import Strip
from textual.widget import Widget
from textual.widgets import Static

from tui_gym.core.experiments import RunHistory, RunRecorder, RunSpec
from tui_gym.session.session import Session
from tui_gym.ui import textual_internals as internals
from tui_gym.ui.app import TuiGymApp

from .pilot_waits import IDLE_WINDOW, wait_on_busy_widgets_only
from .screen import screen_text
from .waiting import wait_for


@pytest.fixture
def stock(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(internals.STOCK_ENV, "all")


def test_every_part_can_be_forced_to_textuals_own_behaviour(stock: None) -> None:
    assert not any(internals.enabled(part) for part in internals.PARTS)
    assert type(internals.main_screen()._compositor).__name__ == "Compositor"
    assert type(internals.main_screen()).focused is Screen.focused  # a full repaint on focus
    assert internals.guarded_driver(HeadlessDriver) is HeadlessDriver
    assert not internals.watch_frames(App(), lambda renderable: None)
    line = Strip([Segment("▐"), Segment("X"), Segment("▌ #1")])
    assert internals.ticked_line(line, lambda: True) is line


async def test_the_app_runs_with_every_fallback_forced(stock: None, tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    spec = RunSpec("train", "frozenlake", "q-learning", seeds=(0,))
    with RunHistory(db) as history, RunRecorder(history, spec) as run:
        run.extend("return", [0.0, 1.0, 0.0, 1.0])
    app = TuiGymApp(Session("frozenlake", seed=0), runner="thread", db=db)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("t", "e", "tab", "escape", "p", "w", "escape", "v")
        view = app.compare_view
        assert view is not None
        await wait_for(pilot, lambda: len(view.runs) == 1, "the recorded run listed")
        await pilot.press("space")  # ticks the run: its curve is drawn
        await wait_for(pilot, lambda: len(view.chart.series) == 1, "the curve")
        assert "#1 Q-learning" in screen_text(app)
        await pilot.press("t", "space")
        await wait_for(pilot, lambda: app.runner.latest.episodes > 0, "training")
        await pilot.press("space", "q")
    assert app.return_code == 0


def test_each_part_falls_back_when_textual_changes_shape(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A compositor without the private method it narrows: the stock compositor stays.
    import textual._compositor

    internals._compositor_class.cache_clear()
    monkeypatch.delattr(textual._compositor.Compositor, "_render_chops")
    assert internals._compositor_class() is None
    internals._compositor_class.cache_clear()  # the tests after it have the real one again
    # A toggle button without its inner mark: the run list's line as Textual drew it.
    import textual.widgets._toggle_button as toggle

    monkeypatch.delattr(toggle.ToggleButton, "BUTTON_INNER")
    line = Strip([Segment("▐"), Segment("X"), Segment("▌ #1")])
    assert internals.ticked_line(line, lambda: True) is line
    # An app without the step that hands frames to its driver: nothing hooked.
    app = App()
    monkeypatch.setattr(app, "_display", None, raising=False)
    assert not internals.watch_frames(app, lambda renderable: None)
    # A driver that cannot be told apart by its arguments: Textual's, unchanged.
    class Odd(HeadlessDriver):
        def __init__(self, application: App, **kwargs: object) -> None:
            super().__init__(application, **kwargs)  # type: ignore[arg-type]

    assert internals.guarded_driver(Odd) is Odd


def test_a_writer_finding_its_terminal_gone_is_told_from_a_crash(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def failure(name: str, error: BaseException) -> threading.ExceptHookArgs:
        return threading.ExceptHookArgs((type(error), error, None, threading.Thread(name=name)))

    assert internals.terminal_write_failed(failure("textual-output", OSError(5, "I/O error")))
    assert not internals.terminal_write_failed(failure("textual-output", ValueError("x")))
    assert not internals.terminal_write_failed(failure("run-history", OSError(5, "I/O error")))
    monkeypatch.setenv(internals.STOCK_ENV, "terminal")
    assert not internals.terminal_write_failed(failure("textual-output", OSError(5, "I/O")))


async def test_a_strip_widget_repaints_whole_when_it_cannot_tell_it_is_in_sight(
    stock: None,
) -> None:
    from .test_ui_strips import OneRows, Rows, rows_shown

    app = OneRows()
    async with app.run_test(size=(20, 6)) as pilot:
        widget = app.query_one(Rows)
        await pilot.pause()
        assert not internals.in_sight(widget)
        widget.asked.clear()
        widget.rows = ["one", "TWO", "three"]
        widget.redraw()
        await pilot.pause()
        assert sorted(widget.asked) == [0, 1, 2]  # Textual's own way: the whole widget
        assert rows_shown(app) == ["one", "TWO", "three"]


class Framed(Widget, can_focus=True):
    DEFAULT_CSS = "Framed { border: round white; } Framed:focus { border: round red; }"


class Box(Widget):
    DEFAULT_CSS = "Box { height: auto; border: round white; } Box:focus-within { border: red; }"


class Tinted(Widget, can_focus=True):
    DEFAULT_CSS = "Tinted > Static { color: white; } Tinted:focus > Static { color: red; }"


class FocusStyles(App[None]):
    def get_default_screen(self) -> Screen:
        return internals.main_screen(id="_default")

    def compose(self) -> ComposeResult:
        with Box(), Framed():
            yield Static("framed")
        with Tinted():
            yield Static("tinted")


async def test_a_focus_change_restyles_inside_a_widget_only_where_a_rule_reads_it() -> None:
    app = FocusStyles()
    async with app.run_test(size=(30, 10)) as pilot:
        framed, tinted = app.query_one(Framed), app.query_one(Tinted)
        assert internals._focus_styles_its_own(framed)  # only its own frame changes
        assert not internals._focus_styles_its_own(tinted)  # what is inside changes too
        for widget, focused, red in ((framed, framed, framed), (tinted, tinted, tinted),
                                     (None, None, None)):
            app.set_focus(widget)
            await pilot.pause()
            assert app.focused is focused
            assert (framed.styles.border.top[1].rgb == (255, 0, 0)) == (red is framed)
            inside = tinted.query_one(Static).styles.color.rgb
            assert (inside == (255, 0, 0)) == (red is tinted)
        app.set_focus(framed)
        await pilot.pause()
        box = app.query_one(Box)
        assert box.styles.border.top[1].rgb == (255, 0, 0)  # its focus is inside
        box.display = False  # its view switched away: restyled after the next frame
        app.set_focus(None)
        await wait_for(pilot, lambda: framed.styles.border.top[1].rgb == (255, 255, 255)
                       and box.styles.border.top[1].rgb == (255, 255, 255),
                       "the hidden widgets restyled as not focused")


class Busy(Static):
    """A widget whose message takes a while to handle (it awaits on the way)."""

    class Work(Message):
        pass

    handled = 0

    async def on_busy_work(self, message: Work) -> None:
        await asyncio.sleep(0.05)
        self.handled += 1


class BusyHost(App[None]):
    def compose(self) -> ComposeResult:
        yield from (Static(f"{n}") for n in range(20))
        yield Busy()


async def test_the_pilots_wait_asks_the_busy_widgets_and_waits_for_them() -> None:
    assert wait_on_busy_widgets_only()  # as the tests run (tests/conftest.py)
    assert textual._wait.SLEEP_GRANULARITY == IDLE_WINDOW
    app = BusyHost()
    async with app.run_test() as pilot:
        busy = app.query_one(Busy)
        busy.post_message(Busy.Work())  # queued
        await pilot.pause()
        assert busy.handled == 1
        busy.post_message(Busy.Work())
        await asyncio.sleep(0.01)  # being handled: nothing queued
        await pilot.pause()
        assert busy.handled == 2
        asked = []
        for node in app.screen.walk_children(Static):
            node.call_later = lambda callback, node=node: asked.append(node) or False
        await pilot.pause()
        assert not asked  # every widget is waiting for its next message
