"""The Plan view driven by keys: methods, sweeps, runs, improvement and the knobs at 80x24 in
the app, and at full size beside the map editor, with an edit while value iteration runs."""

from __future__ import annotations

import numpy as np

from tests.hosts import VIEW_SIZE, PlanHost
from tests.waiting import press_busy, wait_busy
from tui_gym.core.mdp import solve
from tui_gym.games import game_named
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.plan_view import PlanView


def status(view: PlanView) -> str:
    return view._status.lines[1]


def latest(view: PlanView):
    assert view.runner is not None
    return view.runner.latest


async def test_the_plan_view_by_its_keys_at_80x24() -> None:
    app = TuiGymApp(Session("corner-grid", seed=0))
    async with app.run_test(size=(80, 24)) as pilot:
        await press_busy(pilot, "P")
        view = app.plan_view
        assert view is not None and app.current_view == "plan"
        await wait_busy(pilot, lambda: view.runner is not None and view._heatmap.has_focus,
                        "the model and the keyboard")
        await press_busy(pilot, "1", "n")  # policy evaluation, one sweep
        await wait_busy(pilot, lambda: "sweep 1 " in status(view), "one sweep shown")
        assert latest(view).v[1] == -1.0 and "policy evaluation" in view._status.lines[0]
        await press_busy(pilot, "c")  # on to convergence
        await wait_busy(pilot, lambda: status(view).startswith("done"), "convergence")
        assert round(float(latest(view).v[1])) == -14
        await press_busy(pilot, "u")  # one improvement: already optimal (Figure 4.1)
        await wait_busy(pilot, lambda: "14 states changed" in status(view), "the improvement")
        assert view._heatmap.plain.count("*") >= 14
        await press_busy(pilot, "s", "plus", "d")
        await wait_busy(pilot, lambda: latest(view).in_place, "in place")
        assert latest(view).speed == 4 and "-14.0" in view._heatmap.plain
        await press_busy(pilot, "o")  # the start policy: the optimum, values 0
        await wait_busy(pilot, lambda: latest(view).sweeps == 0, "a restart")
        assert view.start == "optimal"
        sections = dict(app.key_help())
        assert [key for key, _ in sections["Plan"]][:2] == ["1 / 2 / 3", "space"]
        assert any("P" in key.split(" / ") for key, _ in sections["Everywhere"])
        await press_busy(pilot, "p")
        assert app.current_view == "play"


async def test_the_keyboard_asked_for_while_a_view_is_built_reaches_it_once_built() -> None:
    """A burst such as `P` then a key that hands the keyboard to the view shown: the Plan
    view, then the Book view, each mounted but not yet composed, takes it once it is (no
    error on the way)."""
    app = TuiGymApp(Session("corner-grid", seed=0))
    async with app.run_test(size=(80, 24)) as pilot:
        for view_name in ("plan", "book"):
            assert view_name not in app._views, f"the {view_name} view is built only when shown"
            app.action_show_view(view_name)
            app.action_focus_view()  # before the view has composed its widgets
            view = app._views[view_name]
            await wait_busy(pilot, lambda v=view: app.focused is not None
                            and v in app.focused.ancestors,
                            f"the {view_name} view with the keyboard")


async def test_a_view_left_while_it_is_built_keeps_its_hands_off_the_keyboard() -> None:
    """A burst `P`, `f`, `p`: the Plan and Book views finish building hidden; the keys (and
    the key bar) stay with the Play view shown."""
    app = TuiGymApp(Session("corner-grid", seed=0))
    async with app.run_test(size=(80, 24)) as pilot:
        for view_name in ("plan", "book", "play"):  # as fast as keys in one read
            app.action_show_view(view_name)
        plan = app._views["plan"]
        await wait_busy(pilot, lambda: plan.runner is not None, "the hidden Plan view built")
        await pilot.pause()
        assert app.current_view == "play"
        assert app.focused is not None and app.play_view in app.focused.ancestors_with_self
        assert not plan._heatmap.has_focus


async def test_an_edit_while_value_iteration_runs_plans_on_from_the_values() -> None:
    session = Session("frozenlake", {"slippery": False}, seed=0)
    app = PlanHost(session)
    async with app.run_test(size=VIEW_SIZE) as pilot:
        view = app.plan_view
        await wait_busy(pilot, lambda: view.runner is not None, "the model")
        assert view.open_editor()
        canvas = view.editor.canvas
        await wait_busy(pilot, lambda: canvas.has_focus, "the editor's keyboard")
        await press_busy(pilot, "right")  # the editor's cursor onto row 0, col 1
        view.focus_default()
        await wait_busy(pilot, lambda: view._heatmap.has_focus, "the values' keyboard")
        await press_busy(pilot, "3", "minus", "minus")  # value iteration at 2 sweeps a second
        await press_busy(pilot, "space")
        await wait_busy(pilot, lambda: latest(view).sweeps >= 2, "two sweeps")
        before = latest(view).sweeps
        view.editor.focus_canvas()
        await wait_busy(pilot, lambda: canvas.has_focus, "the editor's keyboard again")
        await press_busy(pilot, "3")  # a hole at row 0, col 1, while the run goes on
        await wait_busy(pilot, lambda: session.game.grid_map(session.env_kwargs).cells[0][1]
                        == "H", "the edit played")
        view.focus_default()
        await wait_busy(pilot, lambda: view._heatmap.has_focus, "the values' keyboard again")
        await press_busy(pilot, "plus", "plus", "plus", "plus")
        await wait_busy(pilot, lambda: latest(view).done and not latest(view).running,
                        "value iteration on the edited lake")
        done = latest(view)
        assert done.sweeps > before, "the run went on from the values it had"
        plan = view.plan
        assert plan is not None and plan.model.n_states == 16
        optimum = solve(plan.model, 1.0)
        assert np.allclose(done.v, optimum.v, atol=1e-3)
        assert "H" in "".join(session.game.grid_map(session.env_kwargs).cells)


async def test_the_gamblers_values_by_sweep_and_a_bad_gamma() -> None:
    app = PlanHost(Session("gambler", seed=0))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        view = app.plan_view
        await wait_busy(pilot, lambda: view.runner is not None, "the model")
        view.focus_default()
        await wait_busy(pilot, lambda: view._heatmap.has_focus, "the values' keyboard")
        await press_busy(pilot, "c")
        await wait_busy(pilot, lambda: latest(view).done, "value iteration")
        await wait_busy(pilot, lambda: "sweep 3" in view._lines.plain, "the chart")
        assert "capital" in view._lines.plain and "stake" in view._lines.plain
        await press_busy(pilot, "e")
        gamma = view.query_one("#plan-gamma")
        assert gamma.has_focus
        gamma.value = "1.5"
        await press_busy(pilot, "enter")
        assert gamma.has_class("-invalid") and latest(view).gamma == 1.0
        assert any("γ must be in (0, 1]" in n.message for n in app._notifications)
        gamma.value = "0.5"
        await press_busy(pilot, "enter", "escape")
        await wait_busy(pilot, lambda: latest(view).gamma == 0.5, "the new γ")
        assert view._heatmap.has_focus and not gamma.has_class("-invalid")
        assert game_named("gambler").plan_gamma == 1.0
