"""Every keystroke kept: keys sent together, as a paste or a fast typist sends them, are
handled in the order typed, and a field's value applies on enter, never mid-typing."""

from __future__ import annotations

from pathlib import Path

from textual import events
from textual.app import App, ComposeResult
from textual.widgets import Checkbox

from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.side_panel import ParamField, WrapperRow
from tui_gym.ui.textual_internals import deliver_key
from tui_gym.ui.widgets.text_field import TextField

from .terminal import Terminal, console_script
from .waiting import open_train, settle, wait_until

_CHARACTERS = {"backspace": "\x7f", "full_stop": ".", "enter": "\r", "tab": "\t"}


def burst(app: App, *keys: str) -> None:
    """Hand the app every key at once, as the terminal's input thread does for a paste."""
    for key in keys:
        event = events.Key(key, _CHARACTERS.get(key, key if len(key) == 1 else None))
        event.set_sender(app)
        deliver_key(app, event)


async def test_a_burst_edits_a_train_view_field_then_a_wrapper_field_applying_on_enter(
) -> None:
    """One app, in turn: a burst in the Train view's form, then one in a wrapper's field."""
    app = TuiGymApp(Session("frozenlake", seed=0), runner="thread")
    async with app.run_test(size=(120, 40)) as pilot:
        await open_train(pilot)
        episodes = app.runner.latest.episodes
        # `e` moves the keyboard to the first field: every key after it goes there.
        burst(app, "e", "end", *["backspace"] * 6, "0", "full_stop", "2", "5")
        field = app.train_view.form.input("learning_rate")
        await wait_until(pilot, lambda: field.value == "0.25", "the typed value")
        await settle(pilot)
        assert app.session.hp.learning_rate != 0.25, "not applied before enter"
        burst(app, "enter")
        await wait_until(pilot, lambda: app.session.hp.learning_rate == 0.25, "enter applies")
        await settle(pilot)
        assert field.value == "0.25" and not app.train_view.form.error("learning_rate")
        assert app.runner.latest.episodes == episodes, "the '.' was typed, not pressed"

        # A wrapper's field: what was typed applies on enter.
        await wait_until(pilot, lambda: app.side_panel.wrappers_listed, "the wrapper rows")
        row = app.query_one("#wrapper-TimeLimit", WrapperRow)
        row.query_one(Checkbox).value = True
        await wait_until(pilot, lambda: [c.name for c in app.session.choices] == ["TimeLimit"],
                         "TimeLimit ticked")
        field = row.query_one(ParamField).input
        field.focus()
        await settle(pilot)
        assert field.value == "100"
        burst(app, "end", *["backspace"] * 4, "1", "0", "enter")
        await wait_until(pilot, lambda: app.session.choices[0].values()["max_episode_steps"]
                         != 100, "enter applies")
        await settle(pilot)
        assert app.session.choices[0].values() == {"max_episode_steps": 10}
        assert field.value == "10"


async def test_a_text_field_edits_in_the_order_typed_by_itself() -> None:
    """Its editing keys are handled in the field, in line with the characters: no trip up
    to the app for the next character to overtake."""

    class Host(App[None]):
        def compose(self) -> ComposeResult:
            yield TextField("0.001")

    app = Host()
    async with app.run_test() as pilot:
        field = app.query_one(TextField)
        field.focus()
        await settle(pilot)
        burst(app, "end", *["backspace"] * 3, "2", "5", "home", "delete", "9")
        await wait_until(pilot, lambda: field.value == "9.25", "the edits, in order")


def test_a_burst_typed_in_a_terminal_is_kept(tmp_path: Path) -> None:
    saved = tmp_path / "agent.tgym"
    # Nothing trains here: the thread runner, so no training process starts at all.
    term = Terminal([console_script(), "--env", "blackjack", "--no-history", "--runner",
                     "thread"],
                    {"TUI_GYM_LOG_DIR": str(tmp_path / "logs")})
    try:
        term.wait_for_text("tui-gym")  # the header: the app is up
        term.type("t")
        term.wait_for_text("Hyperparameters")
        # e, End, six Backspaces, the new value and Enter, then ctrl+s (save the agent
        # and its settings), in one write.
        term.type("e\x1b[F" + "\x7f" * 6 + "0.25\r\x13")
        term.wait_for_text("Save the Blackjack agent")
        term.type(str(saved) + "\r")
        term.wait_for(saved.exists, "the saved agent")
        term.type("q")
        assert term.exit_code() == 0
    finally:
        term.close()
    assert Session.load(saved).hp.learning_rate == 0.25
