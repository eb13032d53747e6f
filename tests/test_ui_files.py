"""Saving and loading from the app with names a person types, and the palette's files.

ctrl+s and ctrl+o open a dialog with a file name field; what goes wrong is said
inside it; an existing file is replaced only after a yes; loading over an agent
that has trained asks too. The help names both keys; the command palette lists
the same ("Save agent…" and "Load agent…" open the dialog), one "Keys" entry,
and a Screenshot that lands in the current folder. Every test works in its own
temporary folder.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.widgets import Input

from tui_gym.algorithms import QLearning
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.confirm_screen import ConfirmScreen
from tui_gym.ui.file_screen import FileScreen
from tui_gym.ui.help_screen import HelpScreen

from .screen import screen_lines
from .test_ui_session_keeping import palette_first, train_to_the_end
from .waiting import wait_for


@pytest.fixture(autouse=True)
def in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    return tmp_path


def blackjack(episodes: int = 300) -> TuiGymApp:
    return TuiGymApp(Session("blackjack", hp=QLearning.hyperparameters(episodes=episodes), seed=0))


async def type_name(pilot, name: str) -> FileScreen:
    """Replace the dialog's suggested name with `name` (typed) and press enter."""
    screen = pilot.app.screen
    assert isinstance(screen, FileScreen)
    field = screen.query_one(Input)
    await wait_for(pilot, lambda: pilot.app.focused is field, "the name field")
    await pilot.press("home", "shift+end", "backspace")  # select all of it, delete it
    await pilot.press(*name, "enter")
    await pilot.pause()
    return screen


async def test_save_asks_for_a_name_and_before_replacing_and_help_and_palette_have_it(
    in_tmp: Path,
):
    app = blackjack()
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("t")
        await train_to_the_end(pilot)
        await pilot.press("ctrl+s")
        await pilot.pause()
        screen = app.screen
        assert isinstance(screen, FileScreen)
        assert screen.query_one(Input).value == "blackjack-agent.tgym"  # a suggestion

        # Bad names are refused inside the dialog, which stays open.
        await type_name(pilot, "")
        assert "Type a file name" in screen.error
        await type_name(pilot, "nope/a")
        assert "There is no folder" in screen.error and str(in_tmp) in screen.error
        (in_tmp / "f").mkdir()
        await type_name(pilot, "f")
        assert "is a folder" in screen.error
        assert app.screen is screen and not list(in_tmp.glob("*.tgym"))

        await type_name(pilot, "bj")  # no suffix: .tgym is added
        saved = in_tmp / "bj.tgym"
        assert saved.is_file() and not isinstance(app.screen, FileScreen)
        assert any(str(saved) in n.message for n in app._notifications)
        assert Session.load(saved).trainer.episodes == 300
        before = saved.read_bytes()

        # The same name again asks; no leaves the file as it was.
        await pilot.press("x", "y")  # a fresh agent, so a save would differ
        await wait_for(pilot, lambda: app.runner.latest.episodes == 0, "the reset")
        await pilot.press("ctrl+s")
        await pilot.pause()
        assert app.screen.query_one(Input).value == "bj.tgym"  # the last name used
        await pilot.press("enter")  # the suggestion: the file saved just now
        assert isinstance(app.screen, ConfirmScreen)
        assert "bj.tgym" in str(app.screen.query_one("#confirm-title").render())
        await pilot.press("n")
        await pilot.pause()
        assert isinstance(app.screen, FileScreen) and saved.read_bytes() == before
        await pilot.press("enter", "y")
        await pilot.pause()
        assert not isinstance(app.screen, FileScreen | ConfirmScreen)
        assert Session.load(saved).trainer.episodes == 0

        # The help names ctrl+s and ctrl+o.
        await pilot.press("question_mark")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        lines = screen_lines(app)
        assert any("ctrl+s" in line and "save the agent to a file you name" in line
                   for line in lines)
        assert any("ctrl+o" in line and "load an agent from a file you name" in line
                   for line in lines)
        await pilot.press("escape")
        await wait_for(pilot, lambda: not isinstance(app.screen, HelpScreen), "help to close")

        # The palette's Save agent… and Load agent… open the dialog; nothing is saved or
        # loaded without a name confirmed.
        files = sorted(in_tmp.iterdir())
        session = app.session
        for entry, saving in (("Save agent", True), ("Load agent", False)):
            await pilot.press("ctrl+p", *entry.split()[0])  # its first word finds it
            await wait_for(pilot, lambda e=entry: palette_first(app).startswith(e),
                           f"the palette to list {entry}")
            await pilot.press("down", "enter")
            await wait_for(pilot, lambda: isinstance(app.screen, FileScreen), "the file dialog")
            screen = app.screen
            assert isinstance(screen, FileScreen) and screen.saving is saving
            await pilot.press("escape")
            await wait_for(pilot, lambda: not isinstance(app.screen, FileScreen),
                           "the dialog to close")
        assert sorted(in_tmp.iterdir()) == files and app.session is session

        # The command palette: one Keys entry, files, and a Screenshot that works.
        titles = [c.title for c in app.get_system_commands(app.screen)]
        assert titles.count("Keys") == 1 and titles.count("Screenshot") == 1
        assert "Save agent…" in titles and "Load agent…" in titles
        await pilot.press("ctrl+p", *"Screen")
        await wait_for(pilot, lambda: palette_first(app).startswith("Screenshot"),
                       "the palette to list Screenshot")
        await pilot.press("down", "enter")
        await wait_for(pilot, lambda: list(in_tmp.glob("*.svg")), "the screenshot")
        svg = next(in_tmp.glob("*.svg")).read_text(encoding="utf-8")
        assert "Q-table" in svg and "Screenshot" not in svg  # the app, not the palette
        await wait_for(pilot, lambda: any("Screenshot saved to" in n.message
                                          for n in app._notifications), "the notice")


async def test_load_says_what_is_wrong_and_asks_before_replacing_a_trained_agent(in_tmp: Path):
    grid = Session("gridworld", hp=QLearning.hyperparameters(episodes=50, discount=0.95), seed=3)
    grid.train()
    grid.save(in_tmp / "g.tgym")
    (in_tmp / "j.tgym").write_bytes(b"not a save file")
    app = blackjack()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("ctrl+o")
        await pilot.pause()
        screen = app.screen
        assert isinstance(screen, FileScreen)
        await type_name(pilot, "no")
        assert "no such file" in screen.error
        await type_name(pilot, "j")
        assert "not a tui-gym save file" in screen.error and "j.tgym" in screen.error
        await pilot.press("escape")
        await pilot.pause()
        assert not isinstance(app.screen, FileScreen)
        assert app.session.game.name == "blackjack"

        # A GridWorld agent while Blackjack shows: the app switches to it (nothing to
        # replace there yet), and Blackjack keeps its own agent.
        blackjack_agent = app.session.agent
        await pilot.press("ctrl+o")
        await pilot.pause()
        await type_name(pilot, "g")  # .tgym found
        assert app.session.game.name == "gridworld"
        assert app.session.trainer.episodes == 50 and app.session.seed == 3
        assert any("Loaded" in n.message for n in app._notifications)
        await pilot.press("b")
        await pilot.pause()
        assert app.session.agent is blackjack_agent

        # Loading over a GridWorld agent that has trained asks first.
        await pilot.press("g", "ctrl+o")
        await pilot.pause()
        assert app.screen.query_one(Input).value == "g.tgym"  # the file it came from
        await pilot.press("enter")
        assert isinstance(app.screen, ConfirmScreen)
        assert "50 episodes" in str(app.screen.query_one("#confirm-detail").render())
        kept = app.session
        await pilot.press("escape")
        await pilot.pause()
        assert app.session is kept
        await pilot.press("ctrl+o", "enter", "y")
        await pilot.pause()
        assert app.session is not kept and app.session.trainer.episodes == 50


async def test_the_last_name_is_suggested_again_for_a_game_whose_name_holds_a_colon():
    app = TuiGymApp(Session(env_id="tests.tiny_env:TinyChain-v0", seed=0))
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("ctrl+s")
        await pilot.pause()
        assert app.screen.query_one(Input).value == "tests.tiny_env-tinychain-v0-agent.tgym"
        await type_name(pilot, "mine")
        assert (Path.cwd() / "mine.tgym").is_file()
        await pilot.press("ctrl+s")
        await pilot.pause()
        assert app.screen.query_one(Input).value == "mine.tgym"
