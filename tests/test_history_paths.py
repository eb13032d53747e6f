"""Where the run history lives: --db, TUI_GYM_DB, XDG_DATA_HOME, the platform's data folder."""

from __future__ import annotations

from pathlib import Path

import pytest

from tui_gym.core.experiments import list_runs, resolve_db_path
from tui_gym.core.experiments.paths import data_dir

HOME = Path("/home/ada")


def resolve(explicit: str | None, env: dict[str, str], platform: str = "linux") -> Path:
    return resolve_db_path(explicit, environ=env, platform=platform, home=HOME)


def test_explicit_path_wins() -> None:
    env = {"TUI_GYM_DB": "/env/runs.db", "XDG_DATA_HOME": "/xdg"}
    assert resolve("/flag/my.db", env) == Path("/flag/my.db")


def test_environment_variable_comes_next() -> None:
    env = {"TUI_GYM_DB": "/env/runs.db", "XDG_DATA_HOME": "/xdg"}
    assert resolve(None, env) == Path("/env/runs.db")
    assert resolve("", env) == Path("/env/runs.db")


def test_xdg_data_home_on_any_platform() -> None:
    for platform in ("linux", "darwin", "win32"):
        env = {"XDG_DATA_HOME": "/xdg", "APPDATA": "C:/Users/ada/AppData/Roaming"}
        assert resolve(None, env, platform) == Path("/xdg/tui-gym/runs.db")


def test_platform_defaults() -> None:
    assert resolve(None, {}) == HOME / ".local/share/tui-gym/runs.db"
    # A relative XDG_DATA_HOME is ignored, as the XDG spec says.
    assert resolve(None, {"XDG_DATA_HOME": "relative"}) == HOME / ".local/share/tui-gym/runs.db"
    assert resolve(None, {}, "darwin") == HOME / "Library/Application Support/tui-gym/runs.db"
    assert resolve(None, {"APPDATA": "/appdata"}, "win32") == Path("/appdata/tui-gym/runs.db")
    assert data_dir({}, "win32", HOME) == HOME / "AppData/Roaming/tui-gym"


def test_the_real_environment_is_read(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("TUI_GYM_DB", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert resolve_db_path(None) == tmp_path / "xdg" / "tui-gym" / "runs.db"
    monkeypatch.setenv("TUI_GYM_DB", str(tmp_path / "env.db"))
    assert resolve_db_path(None) == tmp_path / "env.db"
    assert list_runs().db == tmp_path / "env.db"
    monkeypatch.setenv("HOME", str(tmp_path))
    assert resolve_db_path("~/x.db") == tmp_path / "x.db"
