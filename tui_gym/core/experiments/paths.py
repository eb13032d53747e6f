"""Where the run history lives: `--db PATH`, else `TUI_GYM_DB`, else the user's data folder."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path

APP_FOLDER = "tui-gym"
DB_FILENAME = "runs.db"
DB_ENV = "TUI_GYM_DB"


def data_dir(
    environ: Mapping[str, str] | None = None, platform: str | None = None, home: Path | None = None,
) -> Path:
    """The user's data folder for tui-gym (not created here)."""
    env = os.environ if environ is None else environ
    plat = sys.platform if platform is None else platform
    home_dir = Path.home() if home is None else home
    xdg = env.get("XDG_DATA_HOME", "")
    if xdg and Path(xdg).is_absolute():  # the XDG spec says to ignore a relative path
        return Path(xdg) / APP_FOLDER
    if plat == "darwin":
        return home_dir / "Library" / "Application Support" / APP_FOLDER
    if plat.startswith("win"):
        appdata = env.get("APPDATA", "")
        base = Path(appdata) if appdata else home_dir / "AppData" / "Roaming"
        return base / APP_FOLDER
    return home_dir / ".local" / "share" / APP_FOLDER


def resolve_db_path(
    explicit: str | None, environ: Mapping[str, str] | None = None, platform: str | None = None,
    home: Path | None = None,
) -> Path:
    """The run history's file: `explicit` (from --db), else $TUI_GYM_DB, else the data folder's."""
    env = os.environ if environ is None else environ
    chosen = explicit or env.get(DB_ENV, "")
    return Path(chosen).expanduser() if chosen else data_dir(env, platform, home) / DB_FILENAME
