"""The save and load keys are where a person looks for them: the README, the help
screen, and the command palette's "Save agent…" and "Load agent…", which open the
file dialog."""

from __future__ import annotations

from pathlib import Path

import pytest

from tui_gym.core.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.file_screen import FileScreen
from tui_gym.ui.help_screen import HelpScreen

from .screen import screen_lines
from .test_ui_session_keeping import palette_first
from .waiting import wait_for

REPO = Path(__file__).resolve().parents[1]


def test_the_readme_names_the_save_and_load_keys() -> None:
    text = " ".join((REPO / "README.md").read_text(encoding="utf-8").split())
    assert "`ctrl+s` save the agent, `ctrl+o` load one" in text  # the key table
    assert "`ctrl+s` saves the agent to a file you name" in text
    assert "`ctrl+o` loads one" in text and "both are in the command palette too" in text


async def test_help_names_the_keys_and_the_palette_opens_the_file_dialog(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    app = TuiGymApp(Session("blackjack", seed=0))
    async with app.run_test(size=(100, 40)) as pilot:
        await pilot.press("question_mark")
        await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), "the help screen")
        lines = screen_lines(app)
        assert any("ctrl+s" in line and "save the agent to a file you name" in line
                   for line in lines)
        assert any("ctrl+o" in line and "load an agent from a file you name" in line
                   for line in lines)
        await pilot.press("escape")
        await wait_for(pilot, lambda: not isinstance(app.screen, HelpScreen), "help to close")

        for entry, saving in (("Save agent", True), ("Load agent", False)):
            await pilot.press("ctrl+p", *entry)
            await wait_for(pilot, lambda e=entry: palette_first(app).startswith(e),
                           f"the palette to list {entry}")
            await pilot.press("down", "enter")
            await wait_for(pilot, lambda: isinstance(app.screen, FileScreen), "the file dialog")
            screen = app.screen
            assert isinstance(screen, FileScreen) and screen.saving is saving
            await pilot.press("escape")
            await wait_for(pilot, lambda: not isinstance(app.screen, FileScreen),
                           "the dialog to close")
        assert not list(tmp_path.iterdir())  # nothing saved without a name confirmed
