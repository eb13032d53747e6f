"""Text that fits at 120x40, whole: the form's ranges and errors, the key bar, the board's
caption; and keys offered only where they do something (`m` for a game with a map)."""

from __future__ import annotations

import textwrap

from tui_gym.algorithms import DynaQ
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.widgets.hyperparameter_form import field_error, range_hint

from .screen import screen_lines, screen_text
from .waiting import wait_for

SIZE = (120, 40)
FIELDS = {field.name: field for field in DynaQ.params}


def test_ranges_and_errors_are_short_and_say_the_bound() -> None:
    assert range_hint(FIELDS["episodes"]) == "[1, 10⁹]"
    assert range_hint(FIELDS["planning_steps"]) == "[0, 1000]"
    assert range_hint(FIELDS["learning_rate"]) == "(0, 1]"
    assert range_hint(FIELDS["initial_value"]) == "±10⁶"
    assert field_error(FIELDS["episodes"], "1234567890") == "'1234567890' is above 1,000,000,000"
    assert field_error(FIELDS["episodes"], "0") == "'0' is below 1"
    assert field_error(FIELDS["learning_rate"], "0.") == "'0.' must be above 0"
    assert field_error(FIELDS["learning_rate"], "abc") == "'abc' is not a number in (0, 1]"


def key_bar_entries(app: TuiGymApp) -> list[str]:
    """The key bar's entries up to the palette's key ("…" one of its own)."""
    line = screen_lines(app)[-1].split("▏")[0].replace("…", "  …")
    return [part.strip() for part in line.split("  ") if part.strip()]


async def test_the_key_bar_the_map_key_the_board_caption_and_the_dyna_q_form_in_blackjack(
) -> None:
    """One app for facts about one game: the key bar leaves keys out whole and keeps help;
    a game without a map offers no `m` (and `m` does nothing); the board's caption takes
    the lines the state needs; Dyna-Q's form and its errors fit whole."""
    session = Session("blackjack", seed=0)
    session.set_algorithm("dyna-q")
    app = TuiGymApp(session, runner="thread")
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        assert not app.check_action("edit_map", ())
        assert "m Map" not in screen_text(app)
        await pilot.press("m")
        await pilot.pause()
        assert app.current_view == "play", "m does nothing where there is no map"
        assert not any("no map" in n.message for n in app._notifications)
        for view in ("p", "t"):
            await pilot.press(view)
            await pilot.pause()
            entries = key_bar_entries(app)
            assert entries[-1] == "…" and "? Help" in entries, entries
            shown = {binding.description for _, binding, *_ in app.screen.active_bindings.values()}
            for entry in entries[:-1]:  # each entry whole: a key and its full description
                assert entry.partition(" ")[2] in shown, (entry, entries)

        caption = app.train_view.query_one("#train-board-caption")
        for _ in range(40):  # until a step's state is too long for one line
            await pilot.press("n")
            await pilot.pause()
            text, width = str(caption.render()), caption.content_region.width
            lines = text.splitlines()  # none until the first step lands
            if lines and len(lines[-1]) > width:  # 'sum 16 vs dealer 10, no usable ace'
                break
        assert len(text.splitlines()[-1]) > width, text
        lines = sum(len(textwrap.wrap(line, width)) for line in text.splitlines())
        assert caption.content_region.height >= lines

        form = app.train_view.form
        form.input("episodes").value = "1234567890"
        await wait_for(pilot, lambda: bool(form.error("episodes")), "the error")
        text = screen_text(app)
        assert "[0, 1000]" in text and "[1, 10⁹]" in text
        assert form.error("episodes") == "'1234567890' is above 1,000,000,000"
        assert "'1234567890' is above" in text and "1,000,000,000" in text  # on two lines

        await pilot.press("g")
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        assert app.check_action("edit_map", ())
