"""The main screen's compositor (`textual_internals.main_screen`): what a terminal shows
after the app's updates is what Textual's own compositor draws for the whole screen, and
a view switch does not draw the containers its widgets cover."""

from __future__ import annotations

from typing import Any

from rich.cells import cell_len
from rich.segment import ControlType, Segment
from textual._compositor import Compositor
from textual.app import App, ComposeResult
from textual.containers import Vertical
from textual.screen import Screen
from textual.widgets import ContentSwitcher, Label, Static

from tui_gym.ui import textual_internals as internals

Cell = tuple[str, Any]


class Counted:
    """A container whose own lines (its background and padding) are counted as drawn."""

    drawn = 0

    def render_lines(self, crop: Any) -> list[Any]:
        self.drawn += crop.height
        return super().render_lines(crop)  # type: ignore[misc]


class CountedView(Counted, Vertical):
    DEFAULT_CSS = "CountedView { padding: 0 1; height: 1fr; }"

    def __init__(self, word: str, id: str) -> None:
        super().__init__(id=id)
        self.word = word

    def compose(self) -> ComposeResult:
        yield Label(f"{self.word} title", id=f"{self.id}-title")
        yield Static(f"{self.word} body", id=f"{self.id}-body", classes="box")


class CountedSwitcher(Counted, ContentSwitcher):
    pass


class Switching(App[None]):
    """Two padded views in a switcher over a line that follows the view, as in the app."""

    CSS = """
    .box { border: round $accent; height: 1fr; background: $panel; }
    .box:focus { border: round $success; }
    #views { height: 1fr; }
    #under { height: 1; }
    """

    def __init__(self) -> None:
        super().__init__()
        self.screens_drawn: list[list[list[Cell]]] = []

    def get_default_screen(self) -> Screen:
        return internals.main_screen(id="_default")

    def compose(self) -> ComposeResult:
        with CountedSwitcher(initial="one", id="views"):
            yield CountedView("one", "one")
            yield CountedView("two", "two")
        yield Label("under: one", id="under")

    def show(self, view: str) -> None:
        self.query_one(CountedSwitcher).current = view
        self.query_one("#under", Label).update(f"under: {view}")
        body = self.query_one(f"#{view}-body", Static)
        body.can_focus = True
        body.focus()


def paint(grid: list[list[Cell]], update: Any, app: App[Any]) -> None:
    """Apply a screen update to `grid` as a terminal would: moves, then cells."""
    x = y = 0
    for segment in update.__rich_console__(app.console, app.console.options):
        assert isinstance(segment, Segment)
        if segment.control:
            for code in segment.control:
                if code[0] == ControlType.CURSOR_MOVE_TO:
                    x, y = code[1], code[2]
            continue
        if segment.text == "\n":
            continue
        for char in segment.text:
            grid[y][x] = (char, segment.style)
            x += cell_len(char)


def textual_full_drawing(app: App[Any]) -> list[list[Cell]]:
    """The whole screen as Textual's own compositor draws it."""
    compositor = app.screen._compositor
    chops = Compositor._render_chops(compositor, compositor.size.region, lambda y: True)
    grid: list[list[Cell]] = []
    for chop in chops:
        row: list[Cell] = []
        for strip in chop.values():
            for segment in strip:
                row.extend((char, segment.style) for char in segment.text)
        grid.append(row)
    return grid


async def test_the_terminal_shows_what_textual_draws_across_view_switches() -> None:
    app = Switching()
    width, height = 40, 12
    grid: list[list[Cell]] = [[(" ", None)] * width for _ in range(height)]
    assert internals.watch_frames(app, lambda update: paint(grid, update, app))
    async with app.run_test(size=(width, height)) as pilot:
        assert type(app.screen._compositor).__name__ == "KeptLayoutCompositor"
        for view in ("two", "one", "two", "one"):
            app.show(view)
            await pilot.pause()
            assert grid == textual_full_drawing(app), f"after switching to {view}"
        assert "under: one" in "".join(char for char, _ in grid[-1])


async def test_a_view_switch_draws_only_what_the_views_widgets_leave_open() -> None:
    app = Switching()
    async with app.run_test(size=(40, 12)) as pilot:
        await pilot.pause()
        switcher = app.query_one(CountedSwitcher)
        two = app.query_one("#two", CountedView)
        switcher.drawn = 0
        app.show("two")
        await pilot.pause()
        assert two.drawn > 0  # its padding shows beside its widgets
        assert switcher.drawn == 0, "the switcher, covered by the view, was drawn"
        for _ in range(20):  # the frames the switch asked for, all drawn
            two.drawn = 0
            await pilot.pause()
            if not two.drawn:
                break
        assert two.drawn == 0, "the view went on drawing with nothing changed"
        app.query_one("#under", Label).update("under: again")
        await pilot.pause()
        assert two.drawn == 0, "a change below the view drew the view again"
