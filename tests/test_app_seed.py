"""Without `--seed` each launch of the app draws a seed of its own, and the header shows
the seed in use, so that a run can be repeated with `--seed`."""

from __future__ import annotations

import secrets
from typing import Any

import pytest

from tui_gym.cli import main
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp


@pytest.mark.parametrize(("argv", "seed"), [([], 48_213), (["--seed", "7"], 7)])
def test_the_app_is_opened_on_a_drawn_seed_unless_one_is_given(
    monkeypatch: pytest.MonkeyPatch, argv: list[str], seed: int
) -> None:
    opened: dict[str, Any] = {}
    monkeypatch.setattr(secrets, "randbelow", lambda n: 48_213)
    monkeypatch.setattr("tui_gym.ui.app.run_app", lambda **kwargs: opened.update(kwargs) or 0)
    assert main(argv) == 0
    assert opened["seed"] == seed


async def test_the_header_shows_the_seed_in_use() -> None:
    app = TuiGymApp(Session("blackjack", seed=48_213))
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        assert app.sub_title == "Blackjack · seed 48213"
        await pilot.press("g")  # another game plays on the same seed
        await pilot.pause()
        assert app.sub_title == "GridWorld · seed 48213"
