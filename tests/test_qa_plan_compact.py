"""The Plan view's row of controls at 80x24: every button it shows, and the speed, fit."""

from __future__ import annotations

from textual.binding import Binding
from textual.widgets import Button

from tests.hosts import PlanHost
from tests.waiting import wait_until
from tui_gym.session.session import Session

# The Plan view's size in the app at 80x24: beside the side panel, under the header, over
# the key bar (the app marks its screen `compact` below 120x36).
COMPACT_VIEW_SIZE = (45, 22)


async def test_restart_and_the_speed_stay_on_screen_in_the_compact_plan_view() -> None:
    app = PlanHost(Session("gridworld", seed=0))
    async with app.run_test(size=COMPACT_VIEW_SIZE) as pilot:
        app.screen.add_class("compact")
        view = app.plan_view
        await wait_until(pilot, lambda: view.runner is not None, "the model")
        await pilot.pause()
        row = view.query_one("#plan-controls")
        shown = [w for w in row.children if w.display]
        assert {w.id for w in shown} >= {"plan-run", "plan-step", "plan-restart",
                                         "plan-slower", "plan-speed", "plan-faster"}
        for widget in shown:
            assert widget.region.right <= row.region.right, f"{widget.id} is cut off"
        hidden = {w.id for w in row.query(Button) if not w.display}
        bound = {b.action for b in view.BINDINGS if isinstance(b, Binding)}
        assert hidden <= {"plan-improve", "plan-converge"}
        assert {"plan('improve')", "plan('converge')"} <= bound
