"""Which process records a run, and whether it is still there: `current_writer`, `WriterCheck`."""

from __future__ import annotations

import os
import socket
from functools import cache

from tui_gym.core.files import pid_alive

_PROC = "/proc"


def _read(path: str) -> str:
    try:
        with open(path, encoding="ascii", errors="replace") as fh:
            return fh.read(4096)
    except OSError:
        return ""


def _start_ticks(pid: int) -> str:
    """A process's start time in clock ticks since boot ("" where /proc has none)."""
    stat = _read(f"{_PROC}/{pid}/stat")
    # The command name (field 2) may hold spaces and parentheses: count after the last ")".
    fields = stat.rpartition(")")[2].split()
    return fields[19] if len(fields) > 19 else ""


@cache
def _boot() -> str:
    return _read(f"{_PROC}/sys/kernel/random/boot_id").strip()


def _host() -> str:
    return socket.gethostname()


def current_writer() -> str:
    """This process's mark: "host boot pid start" (boot and start empty where unknown)."""
    pid = os.getpid()
    return f"{_host()} {_boot()} {pid} {_start_ticks(pid)}"


class WriterCheck:
    """Tells whether the writer of a run is gone; remembers each answer for one listing."""

    def __init__(self) -> None:
        self._host = _host()
        self._boot = _boot()
        self._answers: dict[str, bool] = {}

    def gone(self, mark: object) -> bool:
        """Whether the process that wrote `mark` has ended (False when it cannot be told)."""
        if not isinstance(mark, str) or not mark:
            return False
        known = self._answers.get(mark)
        if known is None:
            known = self._answers[mark] = self._gone(mark)
        return known

    def _gone(self, mark: str) -> bool:
        parts = mark.split(" ")
        if len(parts) != 4 or parts[0] != self._host or not parts[2].isdigit():
            return False
        boot, pid, start = parts[1], int(parts[2]), parts[3]
        if boot and self._boot and boot != self._boot:
            return True  # written before the machine restarted
        if not pid_alive(pid):
            return True
        return bool(start) and _start_ticks(pid) not in ("", start)
