"""The app as a whole: views, game switching, help, the wrapper panel, sizes, key storms."""

from __future__ import annotations

import random

from textual.widgets import Checkbox, ContentSwitcher, Input, RadioButton, Static

from tui_gym.algorithms import QLearning
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.help_screen import HelpScreen
from tui_gym.ui.side_panel import ParamField, SidePanel, WrapperRow
from tui_gym.ui.too_small_screen import TooSmallScreen

from .screen import screen_lines, screen_text
from .waiting import open_train, wait_for


def chain_text(app: TuiGymApp) -> str:
    return str(app.query_one("#chain", Static).render())


def row(app: TuiGymApp, name: str) -> WrapperRow:
    return app.query_one(f"#wrapper-{name}", WrapperRow)


async def test_keys_key_bar_help_wrappers_the_game_picker_and_the_gridworld_panel():
    """One app for facts about one state: views and games switch by key, the key bar
    follows the view, help lists every app key, a misfit wrapper is refused with its
    reason, a wrapper that changes the observations resets the agent with a notice, and
    the picker switches game. Then, on the GridWorld the picker switched to: an invalid
    parameter is marked and not applied, ticking a wrapper rebuilds and keeps the agent,
    the size changes from the panel, and inputs capture typing instead of app keys. The
    header shows the seed in use throughout."""
    app = TuiGymApp(Session("blackjack", seed=48_213))
    async with app.run_test(size=(120, 40)) as pilot:
        # Views and games switch by key; the key bar (a kept picture) and the keyboard
        # follow the view.
        switcher = app.query_one("#views", ContentSwitcher)
        assert switcher.current == "play"
        await pilot.pause()
        assert app.sub_title == "Blackjack · seed 48213"
        play_keys = screen_lines(app)[-1]
        assert "Deal" in play_keys and "Start/Pause" not in play_keys
        await open_train(pilot)
        assert switcher.current == "train"
        train_keys = screen_lines(app)[-1]
        assert "Start/Pause" in train_keys and "Deal" not in train_keys
        assert app.focused is app.train_view.heatmap
        await pilot.press("p")
        assert switcher.current == "play"
        await pilot.pause()
        assert screen_lines(app)[-1] == play_keys  # the kept picture, and the right one
        assert app.focused is app.play_view.board
        await pilot.press("g")  # a new game's session is built off the event loop
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        assert app.sub_title == "GridWorld · seed 48213"  # another game, the same seed
        await pilot.press("b")
        await wait_for(pilot, lambda: app.session.game.name == "blackjack", "Blackjack")

        # Help lists every app key and closes.
        await pilot.press("f1")
        assert isinstance(app.screen, HelpScreen)
        text = screen_text(app)
        for words in (
            "Play view",
            "Blackjack",
            "wrapper panel",
            "quit",
            "start / pause",
            "reset the agent",
            "faster",
        ):
            assert words in text, words
        await pilot.press("escape")
        assert not isinstance(app.screen, HelpScreen)
        await pilot.press("question_mark")
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("question_mark")
        assert not isinstance(app.screen, HelpScreen)

        # A misfit wrapper shows its reason and is not applied.
        shaping = row(app, "DistanceShaping")
        assert shaping.has_class("-misfit")  # the reason shows before it is ticked
        shaping.query_one(Checkbox).value = True
        await pilot.pause()
        shaping = row(app, "DistanceShaping")
        assert shaping.has_class("-misfit")
        assert "info['distance']" in str(shaping.query_one(".reason", Static).render())
        assert "DistanceShaping" not in app.session.chain_repr()
        assert "not applied" in chain_text(app)

        # A wrapper that changes observations resets the agent, with a notice.
        agent = app.session.agent
        earlier = {n.identity for n in app._notifications}  # the game switches' notices
        row(app, "FlattenObservation").query_one(Checkbox).value = True
        await pilot.pause()
        assert app.session.agent is not agent
        assert any("reset" in n.message for n in app._notifications
                   if n.identity not in earlier)

        # The game picker switches game: brought into view first, as a person scrolls to
        # it (the panel follows its focused row, the wrapper just ticked).
        picker = app.query_one("#game-gridworld", RadioButton)
        picker.scroll_visible(animate=False)
        await wait_for(pilot, lambda: app.screen.region.contains_region(picker.region)
                       and bool(picker.region), "the picker in view")
        await pilot.click("#game-gridworld")
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        assert app.query_one("#game-gridworld", RadioButton).value

        # GridWorld's panel: an invalid parameter is marked and not applied.
        row(app, "TimeLimit").query_one(Checkbox).value = True
        await pilot.pause()
        assert [c.name for c in app.session.choices] == ["TimeLimit"]
        before = app.session.chain_repr()
        field = row(app, "TimeLimit").query_one(ParamField)
        field.input.focus()
        field.input.value = "lots"
        await pilot.press("enter")
        await pilot.pause()
        assert field.input.has_class("-invalid")
        error = str(row(app, "TimeLimit").query_one(".param-error", Static).render())
        assert "max_episode_steps" in error and "integer" in error
        assert app.session.chain_repr() == before
        field.input.value = "20"
        await pilot.press("enter")
        await pilot.pause()
        assert app.session.applied[0].values()["max_episode_steps"] == 20

        # Ticking a wrapper rebuilds and keeps the agent.
        agent = app.session.agent
        assert "StepPenalty" not in chain_text(app)
        await pilot.press("escape", "w")  # out of the field, to the wrappers
        box = row(app, "StepPenalty").query_one(Checkbox)
        box.value = True
        await pilot.pause()
        assert "StepPenalty" in chain_text(app)
        assert app.session.chain_repr().startswith("<StepPenalty<")
        assert app.session.agent is agent  # rewards changed, observations did not
        # Human play uses the wrapped env too.
        assert "StepPenalty" in str(app.play_view.game.env)

        # The size changes from the panel (the wrapper stays on).
        size_field = app.query_one("#env-params").query_one(ParamField)
        size_field.input.value = "7"
        size_field.input.focus()
        await pilot.press("enter")
        await pilot.pause()
        assert app.session.env_kwargs["size"] == 7
        assert app.play_view.game.scene()["size"] == 7

        # Inputs capture typing instead of app keys.
        field = row(app, "StepPenalty").query_one(Input)
        field.focus()
        field.value = ""
        await pilot.press("q", "t", "p")  # would quit / switch views if not typed
        assert field.value == "qtp"
        assert app.query_one("#views", ContentSwitcher).current == "play"


async def test_sizes_too_small_and_compact_and_random_keys_never_break_the_app():
    """One app through the sizes: below 80×24 a message covers it and takes every key but
    q; at 80×24, the smallest size it lays out, the compact layout with the side panel,
    where random keys (seeded) in each view of two games never break it."""
    keys = [
        "h",
        "s",
        "n",
        "enter",
        "up",
        "down",
        "left",
        "right",
        "w",
        "a",
        "d",
        "r",
        "space",
        "full_stop",
        "plus",
        "minus",
        "x",
        "tab",
        "shift+tab",
        "escape",
        "t",
        "p",
        "question_mark",
        "1",
        "z",
        "backspace",
    ]
    rng = random.Random(1234)
    # A small budget: space may start training, which should end soon.
    app = TuiGymApp(Session("blackjack", hp=QLearning.hyperparameters(episodes=2_000), seed=0))
    async with app.run_test(size=(60, 20)) as pilot:
        await pilot.pause()
        assert isinstance(app.screen, TooSmallScreen)
        message = app.screen.query_one("#too-small", Static)
        assert "80×24" in str(message.render()) and "q quits" in str(message.render())
        # Keys a person cannot see the effect of do nothing: no game switch, no view
        # switch, no move on the board, no training, no palette.
        game = app.play_view.game
        player = list(game.scene()["player"])
        for key in ("g", "t", "space", "h", "s", "w", "question_mark", "ctrl+p", "ctrl+s"):
            await pilot.press(key)
        await pilot.pause()
        assert isinstance(app.screen, TooSmallScreen)
        assert app.session.game.name == "blackjack"
        assert app.current_view == "play"
        assert game.scene()["player"] == player and not game.done
        assert not app.runner.running and app.runner.latest.episodes == 0

        # At 80×24 the app is back, in its compact layout with the side panel.
        await pilot.resize_terminal(80, 24)
        await pilot.pause()
        assert not isinstance(app.screen, TooSmallScreen)
        assert not app.screen.has_class("too-small")
        assert app.screen.has_class("compact")
        assert app.query_one(SidePanel).region.width > 0
        assert app.focused is app.play_view.board  # back where it was
        await pilot.press("g")  # and keys act again
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        app.train_view.form.input("episodes").value = "2000"  # applied at a start

        # Random keys in each view of both games (b switches back).
        for name in ("gridworld", "blackjack"):
            if name != app.session.game.name:
                app.runner.pause()
                await pilot.press("b")
                await wait_for(pilot, lambda n=name: app.session.game.name == n, "the game switch")
            for view in ("p", "t"):
                # Twenty keys in one go: the app handles each before the next arrives.
                await pilot.press("escape", view, *(rng.choice(keys) for _ in range(20)))
                await pilot.pause()
            # Still answering: the views switch on request.
            await pilot.press("escape", "escape", "t")
            await pilot.pause()
            if isinstance(app.screen, HelpScreen):
                await pilot.press("escape")
            await pilot.press("p")
            await pilot.pause()
            assert app.query_one("#views", ContentSwitcher).current == "play", name
        app.runner.pause()

        # Too small again (narrow only): the message, and quitting still works.
        await pilot.resize_terminal(70, 30)
        await pilot.pause()
        assert isinstance(app.screen, TooSmallScreen)
        await pilot.press("q")
        await pilot.pause()
    assert app.return_code == 0


async def test_the_train_view_shown_again_appears_then_draws_what_was_trained_meanwhile():
    """Shown again, the Train view's first frame shows what it drew last; the snapshot
    trained while it was hidden is drawn right after that frame, not into it."""
    from tui_gym.ui.textual_internals import watch_frames

    app = TuiGymApp(Session("frozenlake", seed=0), runner="thread")
    events: list[tuple[str, int]] = []  # ("frame", 0) on the Train view, ("drawn", version)
    watch_frames(app, lambda update: events.append(("frame", 0))
                 if app.current_view == "train" else None)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("t")
        view = app.train_view
        show = view.show_snapshot
        view.show_snapshot = lambda snapshot, runner: (  # type: ignore[method-assign]
            events.append(("drawn", snapshot.version)), show(snapshot, runner))
        await pilot.press("p")
        runner = app.runner
        version = runner.latest.version
        runner.run_one_episode()
        await wait_for(pilot, lambda: runner.latest.version != version, "an episode trained")
        latest = runner.latest.version
        events.clear()
        await pilot.press("t")
        await wait_for(pilot, lambda: ("drawn", latest) in events, "the latest snapshot drawn")
        assert events.index(("frame", 0)) < events.index(("drawn", latest))
        await wait_for(pilot, lambda: events[-1] == ("frame", 0), "a frame with the snapshot")
        assert app.focused is view.heatmap
