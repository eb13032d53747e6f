"""Games switched faster than training hands the agent back: the last game asked for is
the one shown (its own key included), whichever waiting switch the event loop runs
first."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests.waiting import wait_for
from tui_gym.games import game_named
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp


async def test_a_switch_asked_for_before_the_last_one_never_shows_its_game(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    app = TuiGymApp(Session("gambler", seed=0), db=tmp_path / "runs.db")
    async with app.run_test(size=(120, 40)) as pilot:
        for name in ("corner-grid", "gambler"):  # both kept from here on
            app.switch_game(game_named(name))
            await wait_for(pilot, lambda n=name: app.session.game.name == n, name)
        waiting: list[Callable[[], None]] = []
        monkeypatch.setattr(app, "_when_idle", lambda then, otherwise=None: waiting.append(then))
        await pilot.press("K", "G", "K", "G")  # a burst of game keys while training runs
        for then in reversed(waiting):  # the runner hands back: any order of the timers
            then()
            await pilot.pause()
        assert app.session.game.name == "gambler"
