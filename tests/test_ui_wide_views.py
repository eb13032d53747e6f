"""The views that take the whole width at 80×24 (Compare and Book): the side panel hides
there and `w` brings it back until it is left, and switching views never restyles the
whole screen (a class on the screen would: every widget's styles again; only a new
size changes the layout's class there)."""

from __future__ import annotations

from pathlib import Path

from textual.dom import DOMNode
from textual.screen import Screen

from tests.waiting import wait_for
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp


async def test_the_compact_book_view_takes_the_width_and_w_brings_the_panel_back(
    tmp_path: Path,
) -> None:
    app = TuiGymApp(Session("blackjack", seed=0), db=tmp_path / "runs.db")
    restyled: list[DOMNode] = []
    update_styles = app.update_styles

    def spy(node: DOMNode, animate: bool = True) -> None:
        restyled.append(node)
        update_styles(node, animate)

    app.update_styles = spy  # type: ignore[method-assign]
    async with app.run_test(size=(80, 24)) as pilot:
        side = app.side_panel
        await wait_for(pilot, lambda: app.screen.has_class("compact"), "the compact layout")
        restyled.clear()
        await pilot.press("f", "w")  # typed at once: the view's first frame keeps off the panel
        await wait_for(pilot, lambda: app.current_view == "book" and side.has_focus_within,
                       "the Book view, the side panel back with the keyboard")
        await pilot.pause()
        await pilot.pause()
        assert side.display and side.has_focus_within
        await pilot.press("escape")
        await wait_for(pilot, lambda: not side.display, "the side panel gone again")
        await pilot.press("p")
        await wait_for(pilot, lambda: app.current_view == "play" and side.display, "Play")
        await pilot.press("f")
        await wait_for(pilot, lambda: not side.display, "the Book view again")
        assert not [node for node in restyled if isinstance(node, Screen)]
        await pilot.resize_terminal(120, 40)  # (the layout's class on the screen changes)
        await wait_for(pilot, lambda: side.display, "the side panel at full size")
