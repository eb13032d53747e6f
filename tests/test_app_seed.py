"""Without `--seed` each launch of the app draws a seed of its own, so that a run can be
repeated with `--seed` (the header shows the seed in use: tests/test_ui_app.py)."""

from __future__ import annotations

import secrets
from typing import Any

import pytest

from tui_gym.cli import main


@pytest.mark.parametrize(("argv", "seed"), [([], 48_213), (["--seed", "7"], 7)])
def test_the_app_is_opened_on_a_drawn_seed_unless_one_is_given(
    monkeypatch: pytest.MonkeyPatch, argv: list[str], seed: int
) -> None:
    opened: dict[str, Any] = {}
    monkeypatch.setattr(secrets, "randbelow", lambda n: 48_213)
    monkeypatch.setattr("tui_gym.ui.app.run_app", lambda **kwargs: opened.update(kwargs) or 0)
    assert main(argv) == 0
    assert opened["seed"] == seed

