"""Crash logs: an unexpected error's full traceback goes to a file, the person gets one line."""

from __future__ import annotations

import contextlib
import os
import platform
import sys
import time
import traceback
from pathlib import Path

KEEP = 20  # crash logs kept; older ones are removed


def log_dir() -> Path:
    """Where crash logs go: `$TUI_GYM_LOG_DIR`, else `$XDG_STATE_HOME/tui-gym`, else
    `~/.local/state/tui-gym` (the newest `KEEP` are kept)."""
    override = os.environ.get("TUI_GYM_LOG_DIR")
    if override:
        return Path(override).expanduser()
    state = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(state).expanduser() / "tui-gym"


def write_crash_log(error: BaseException) -> Path:
    """Write `error`'s traceback to a new log file and return its path (OSError if it cannot)."""
    from tui_gym import __version__

    folder = log_dir()
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    path = folder / f"crash-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.log"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8", errors="replace") as out:
        out.writelines([
            f"tui-gym {__version__} crashed at {time.strftime('%Y-%m-%d %H:%M:%S %z')}\n",
            f"python {platform.python_version()} on {platform.platform()}\n",
            f"command: {' '.join(sys.argv)}\n\n", *traceback.format_exception(error),
        ])
    for old in sorted(folder.glob("crash-*.log"), reverse=True)[KEEP:]:  # names sort by time
        with contextlib.suppress(OSError):
            old.unlink()
    return path


def report_crash(error: BaseException) -> str:
    """Write the log (when possible) and return the one line to print: what went wrong,
    and where the details are."""
    what = " ".join(f"{type(error).__name__}: {error}".split())
    if len(what) > 200:
        what = what[:199] + "…"
    try:
        where = f"the full traceback is in {write_crash_log(error)}"
    except OSError as exc:
        where = f"the traceback could not be written to {log_dir()} ({' '.join(str(exc).split())})"
    return f"tui-gym: stopped by an unexpected error ({what}); {where}"
