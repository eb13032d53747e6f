"""The Train view, driven like a person would: keys, clicks, and what the screen says.

Every wait polls a condition with a deadline (`wait_for`); nothing sleeps.
Training runs on the runner's worker thread, and the exact figures of a snapshot
on one of the view's own, so these tests also check that the view follows them
without ever training or evaluating on the event loop. Checks of one setup share
one app, run in sequence; the view's own drawing of a session is checked on the
view mounted alone.
"""

from __future__ import annotations

import threading

import pytest

from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games import game_for
from tui_gym.session.session import Session, default_settings
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.confirm_screen import ConfirmScreen
from tui_gym.ui.train_view import TrainView
from tui_gym.ui.widgets.heatmap_view import HeatmapView
from tui_gym.ui.widgets.hyperparameter_form import HyperparameterForm

from .hosts import VIEW_SIZE, TrainHost
from .screen import screen_text
from .waiting import DEADLINE, figures_shown, open_train, send_key, wait_for, wait_until


async def paused(pilot) -> None:
    """Pause training and wait until the worker has stopped."""
    app = pilot.app
    if app.runner.running:
        send_key(pilot, "space")  # the pilot would wait out training
    await wait_for(pilot, lambda: not app.runner.running, "training to pause")
    assert app.runner.wait_idle(DEADLINE)
    view = app.query_one(TrainView)
    await wait_for(pilot, lambda: view._version == app.runner.latest.version,
                   "the view to show the last snapshot")
    await figures_shown(pilot, view)


def blackjack_app(episodes: int = 1_000_000, engine: str = "env") -> TuiGymApp:
    # The env loop by default: slow enough to watch a run between two checks.
    hp = QLearning.hyperparameters(episodes=episodes)
    return TuiGymApp(Session("blackjack", seed=0, hp=hp, engine=engine))


async def test_the_model_loop_reaches_near_optimal_play_live() -> None:
    app = blackjack_app(episodes=500_000, engine="auto")
    async with app.run_test(size=(120, 40)) as pilot:
        view = await open_train(pilot)
        send_key(pilot, "space")
        await wait_for(pilot, lambda: not app.runner.running and app.runner.finished,
                       "the budget to finish", timeout=60)
        await wait_for(pilot, lambda: view._snapshot.episodes == 500_000, "the last frame")
        await figures_shown(pilot, view)
        assert "model" in view.stats.plain
        gap = app.session.reference().figures["gap"]
        assert gap < 0.002
        assert "gap" in screen_text(app)


async def test_one_episode_reset_live_training_speed_keys_then_gridworld_targets() -> None:
    """One app, in turn: one episode at a time and the reset; training live and the
    pause; the speed keys, animated training and switching game; on GridWorld then,
    the target moved by keys and clicks, training filling the heatmap, and the compact
    layout."""
    app = blackjack_app()
    async with app.run_test(size=(120, 40)) as pilot:
        view = await open_train(pilot)
        await wait_for(pilot, lambda: "usable ace" in view.heatmap.plain, "the heatmap drawn")
        untrained = view.heatmap.plain
        assert "A  2  3" in untrained
        assert "episodes 0" in view.stats.plain
        assert app.runner.speed.name == "max"

        # One episode, and the reset.
        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "one episode")
        assert app.runner.wait_idle(DEADLINE)
        for _ in range(5):
            await pilot.pause()
        assert app.runner.latest.episodes == 1
        assert not app.runner.running
        await wait_for(pilot, lambda: "episodes 1\n" in view.stats.plain, "the stats to say 1")

        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 2, "a second episode")

        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.latest.episodes > 200, "some training")
        send_key(pilot, "x")  # while it may still run: the reset pauses first
        await wait_until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        await pilot.press("y")  # yes: it has trained, so it asks first
        await wait_for(pilot, lambda: app.runner.latest.episodes == 0, "the reset")
        assert not app.runner.running
        await wait_for(pilot, lambda: "episodes 0\n" in view.stats.plain, "fresh stats")
        assert not view.charts.data("return")

        # Training runs live, and pauses.
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.latest.episodes > 500, "500 episodes")
        await wait_until(pilot, lambda: len(view.charts.data("return")) > 1,
                         "the return sparkline")
        first = {k: view.charts.data(k)
                 for k in ("return", "length", "td_error", "epsilon")}
        assert all(first.values()), first
        seen = app.runner.latest.episodes

        await wait_until(pilot, lambda: view._snapshot.episodes > seen + 500, "more episodes")
        later = view.charts.data("epsilon")
        assert later != first["epsilon"]  # the curves follow the run
        shown = view._snapshot.episodes
        assert f"episodes {shown:,}" in view.stats.plain
        assert "running" in view.stats.plain
        await wait_until(pilot, lambda: "exact value" in view.stats.plain, "the exact value")
        assert "optimal value" in view.stats.plain
        assert view.heatmap.plain != untrained  # the greedy policy has moved
        assert "env" in view.stats.plain and "max" in view.stats.plain

        await paused(pilot)
        stopped = app.runner.latest.episodes
        for _ in range(5):
            await pilot.pause()
            assert app.runner.latest.episodes == stopped
        assert "paused" in view.stats.plain
        assert view._snapshot.episodes == stopped
        on_screen = screen_text(app)
        assert f"{stopped:,} / 1,000,000 episodes" in on_screen
        assert "paused" in on_screen and "mean return" in on_screen
        assert "Q-values, usable ace" in on_screen and "exact value" in on_screen

        # The speed keys.
        assert view.speed_name == "max"
        await pilot.press("minus")
        assert app.runner.speed.name == view.speed_name == "animated (fast)"
        await pilot.press("minus", "minus")
        assert view.speed_name == "animated (slow)"
        await pilot.press("minus")  # already the slowest
        assert view.speed_name == "animated (slow)"
        await pilot.press("plus")
        assert view.speed_name == "animated"
        assert "speed animated" in view.stats.plain
        await pilot.press("plus", "plus")
        assert view.speed_name == "max"

        # Animated training shows the agent on a board; max hides it.
        await pilot.press("minus")  # animated (fast)
        send_key(pilot, "space")  # the pilot would wait out training
        await wait_for(pilot, lambda: app.runner.last_scene is not None, "an animated step")
        box = view.query_one("#train-board-box")
        await wait_for(pilot, lambda: box.has_class("-shown"), "the board")
        await paused(pilot)
        await pilot.press("plus")  # max: no board
        assert not box.has_class("-shown")

        # Switching game reloads the view.
        assert view.heatmap.focus_cell is None
        await pilot.press("g")
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        await figures_shown(pilot, view)
        assert "target at (4, 4)" in view.heatmap.plain
        assert view.heatmap.focus_cell == (0, 4)
        assert any("target" in text for _, text in view.key_help())
        hp = app.session.hp
        assert view.form.input("episodes").value == str(hp.episodes)
        assert hp == default_settings(game_for("gridworld"), "q-learning")

        # GridWorld's heatmaps follow a target moved by keys and clicks; its own budget.
        view.form.input("episodes").value = "300"  # applied when training starts
        heatmap = view.query_one(HeatmapView)
        assert app.focused is heatmap
        assert view.focus_target == (4, 4)
        assert heatmap.focus_cell == (0, 4)
        assert "target at (4, 4)" in heatmap.plain

        await pilot.press("left")
        assert view.focus_target == (3, 4)
        await pilot.press("j")  # down
        assert view.focus_target == (3, 3)
        await pilot.press("up", "up", "up")  # clipped at the top edge
        assert view.focus_target == (3, 4)
        await figures_shown(pilot, view)
        assert "target at (3, 4)" in heatmap.plain
        assert heatmap.focus_cell == (0, 3)

        # a click on the bottom-left cell puts the target at (0, 0)
        place = heatmap._placements[0]
        cell_w, cell_h = heatmap._cell_geometry
        x = heatmap.styles.padding.left + place.x + cell_w // 2
        y = place.y + 4 * cell_h
        assert await pilot.click(HeatmapView, offset=(x, y))
        assert view.focus_target == (0, 0)
        await figures_shown(pilot, view)
        assert "target at (0, 0)" in heatmap.plain
        assert "optimal pair fraction" in view.stats.plain

        # Training fills the heatmap, and the view says when the budget is done.
        before = view.heatmap.plain
        send_key(pilot, "space")  # the pilot would wait out training
        await wait_for(pilot, lambda: app.runner.latest.episodes == 300, "the whole budget")
        await paused(pilot)
        assert view.heatmap.plain != before
        assert "finished" in view.stats.plain

        # The trained heatmap at 80x24.
        await pilot.resize_terminal(80, 24)
        assert app.screen.has_class("compact")
        assert "target at" in view.heatmap.plain


async def test_invalid_fields_buttons_and_the_compact_layout() -> None:
    """One app, in turn: bad fields are marked, block training and are checked together;
    the buttons do what the keys do; the compact layout at 80x24."""
    app = blackjack_app(episodes=300)
    async with app.run_test(size=(120, 40)) as pilot:
        view = await open_train(pilot)
        form = view.query_one(HyperparameterForm)
        # Every bad value in turn: each is marked and blocks training, and the fix
        # clears the mark before the next one is typed.
        for bad in ("abc", "5", ""):
            await pilot.press("e")  # edit the hyperparameters
            await wait_for(pilot, lambda: app.focused is form.input("learning_rate"),
                           "the field")
            await pilot.press("backspace", *bad)  # the text is selected on focus: replace it
            await wait_for(pilot, lambda: form.is_invalid("learning_rate"), f"the mark ({bad!r})")
            error = form.error("learning_rate")  # 'abc' no number, '5' out of range
            assert "(0, 1]" in error or "is above 1" in error, error
            assert error in screen_text(app)  # said under the field
            form.input("learning_rate").blur()  # the keyboard leaves the field, unapplied
            await pilot.press("space")
            await pilot.pause()
            assert not app.runner.running
            assert app.runner.latest.episodes == 0
            assert form.is_invalid("learning_rate")

            form.input("learning_rate").focus()
            await wait_for(pilot, lambda: app.focused is form.input("learning_rate"),
                           "the field")
            if bad:
                form.input("learning_rate").value = "0.01"  # typing it is checked last
                await pilot.press("enter")
            else:
                await pilot.press("backspace", *"0.01", "enter")
            await wait_for(pilot, lambda: not form.is_invalid("learning_rate"), "the fix")
            assert form.error("learning_rate") == ""
            assert app.focused is view.heatmap
        # Escape drops what was typed and not applied: the field shows what is in force.
        await pilot.press("e", "backspace", "5")
        await wait_for(pilot, lambda: form.is_invalid("learning_rate"), "the mark")
        await pilot.press("escape")
        assert app.focused is view.heatmap
        assert form.input("learning_rate").value == "0.01"
        assert not form.is_invalid("learning_rate") and form.error("learning_rate") == ""
        send_key(pilot, "space")  # the pilot would wait out training
        await wait_for(pilot, lambda: app.runner.latest.episodes == 300, "the whole budget")
        assert app.session.hp.learning_rate == pytest.approx(0.01)
        await paused(pilot)
        assert "finished" in view.stats.plain

        # The buttons do what the keys do.
        assert await pilot.click("#btn-reset")
        await pilot.press("y")  # yes: it has trained, so it asks first
        await wait_for(pilot, lambda: app.runner.latest.episodes == 0, "the reset")
        assert await pilot.click("#btn-slower")
        assert view.speed_name == "animated (fast)"
        assert await pilot.click("#btn-faster")
        assert view.speed_name == "max"
        assert await pilot.click("#btn-episode")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "one episode")

        # At 80x24 the compact layout hides the form until `e`; the run goes on there.
        await pilot.resize_terminal(80, 24)
        assert app.screen.has_class("compact")
        assert not view.form.region.height  # hidden until `e`
        assert await pilot.click("#btn-toggle")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 300, "the whole budget")
        await paused(pilot)
        assert "finished" in view.stats.plain
        assert "episodes" in view.stats.plain
        assert "A  2  3" in view.heatmap.plain
        await pilot.press("e")
        await wait_for(pilot, lambda: app.focused is view.form.input("learning_rate"),
                       "the form")
        await pilot.press("escape")
        assert app.focused is view.heatmap

        # Fields are checked together, and the form loads a whole set.
        assert form.input("episodes").value == "300"
        form.input("epsilon_start").value = "0.1"
        form.input("epsilon_final").value = "0.5"
        await pilot.pause()
        assert view.read_hyperparameters() is None
        await pilot.pause()
        assert form.is_invalid("epsilon_final")
        assert "must not exceed" in form.error("epsilon_final")
        form.input("epsilon_final").value = "0.05"
        await wait_for(pilot, lambda: form.valid, "the fields to settle")
        hp = view.read_hyperparameters()
        assert hp is not None and hp.epsilon_start == 0.1 and hp.episodes == 300
        form.load(QLearning.hyperparameters(episodes=77))
        assert form.input("episodes").value == "77"


async def test_hidden_heatmaps_say_why() -> None:
    app = TrainHost(Session("blackjack", seed=0, choices=(WrapperChoice("DelayObservation"),)))
    async with app.run_test(size=(120, 40)) as pilot:
        view = app.query_one(TrainView)
        await figures_shown(pilot, view)
        reason = app.session.hidden_reason()
        assert reason
        assert view.heatmap.plain == reason
        assert reason in view.stats.plain


async def test_the_heatmap_takes_the_keyboard_without_scrolling_the_state_away() -> None:
    """A heatmap taller than the room left under the stats is not scrolled to: the run's
    state (the stats panel's title) stays on the screen."""
    app = TrainHost(Session("blackjack", seed=1))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        view = app.query_one(TrainView)
        await figures_shown(pilot, view)
        body = view.query_one("#train-body")
        assert body.max_scroll_y > 0  # the Q-table reaches under the screen's edge
        app.set_focus(None)
        view.focus_default()
        await pilot.pause()
        assert app.focused is view.heatmap and body.scroll_y == 0


async def test_a_run_that_ends_short_of_the_bound_says_why() -> None:
    session = Session("frozenlake", seed=0, hp=QLearning.hyperparameters(episodes=20))
    session.train()  # to the budget's end
    app = TrainHost(session)
    async with app.run_test(size=(120, 40)) as pilot:
        await figures_shown(pilot, app.query_one(TrainView))
        assert "It ends short of the bound" in app.query_one(TrainView).stats.plain
        assert "more episodes" in screen_text(app)


class SlowReference:
    """`Session.reference` that blocks, on one game, until `release` (on its caller's
    thread: the event loop would freeze there), counting the snapshots it was asked."""

    def __init__(self, monkeypatch, game: str) -> None:
        self.game, self.release, self.asked = game, threading.Event(), []
        reference = Session.reference

        def slow(session: Session, snapshot=None):
            if session.game.name == self.game:
                self.asked.append(snapshot.version)
                self.release.wait(DEADLINE)
            return reference(session, snapshot)

        monkeypatch.setattr(Session, "reference", slow)


async def test_a_slow_reference_blocks_no_key_and_the_latest_snapshot_wins(monkeypatch) -> None:
    slow = SlowReference(monkeypatch, "frozenlake")
    app = TrainHost(Session("frozenlake", seed=0, hp=QLearning.hyperparameters(episodes=50)))
    try:
        async with app.run_test(size=(120, 40)) as pilot:
            view = app.train_view
            await wait_until(pilot, lambda: slow.asked, "the reference asked for")
            first = slow.asked[0]
            await pilot.press("e")  # the key takes effect while the reference is computed
            assert app.focused is view.form.input("learning_rate")
            assert not slow.release.is_set() and not view.figures_shown
            runner = app.runner
            for _ in range(3):  # three newer snapshots: only the last one is computed
                assert runner.run_one_episode() and runner.wait_idle(DEADLINE)
                view.show_snapshot(runner.latest, runner)
            slow.release.set()
            await figures_shown(pilot, view)
            assert slow.asked == [first, runner.latest.version]
            assert "exact value" in view.stats.plain
    finally:
        slow.release.set()


async def test_a_stale_result_is_dropped_after_a_game_switch(monkeypatch) -> None:
    slow = SlowReference(monkeypatch, "frozenlake")
    app = TrainHost(Session("frozenlake", seed=0))
    try:
        async with app.run_test(size=(120, 40)) as pilot:
            view = app.train_view
            shown = []
            draw = view._show_figures
            view._show_figures = lambda figures: (shown.append(figures), draw(figures))
            await wait_until(pilot, lambda: slow.asked, "the reference asked for")
            app.session = app.runner.session = Session("cliffwalking", seed=0)
            view.reload()  # as the app does on a game switch
            slow.release.set()
            await figures_shown(pilot, view)
            assert [f.request.session.game.name for f in shown] == ["cliffwalking"]
            assert view._figures.reference == app.session.reference(app.runner.latest)
    finally:
        slow.release.set()
