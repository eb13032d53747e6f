"""Shared pytest setup: the `slow` marker, run only when TUI_GYM_SLOW=1."""

from __future__ import annotations

import os

import pytest

SLOW_ENV = "TUI_GYM_SLOW"


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"slow: takes tens of seconds; skipped unless the environment variable {SLOW_ENV}=1",
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if os.environ.get(SLOW_ENV) == "1":
        return
    skip = pytest.mark.skip(reason=f"slow; set {SLOW_ENV}=1 to run")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(autouse=True, scope="session")
def _run_history_in_tmp(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every run the tests record goes to a file of their own, never the user's history."""
    os.environ["TUI_GYM_DB"] = str(tmp_path_factory.mktemp("history") / "runs.db")
