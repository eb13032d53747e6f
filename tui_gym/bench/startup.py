"""Start-up: from launching the app to its first frame on a terminal."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
from dataclasses import dataclass

SIZE = (120, 40)  # columns, rows
FIRST_PAINT = b"\x1b[1;1H\x1b["  # cursor home, then the first styled cells
TIMEOUT = 20.0  # seconds; only reached when something is broken


@dataclass(frozen=True)
class StartupResult:
    """Seconds from launch to the first frame, one per launch."""

    samples: tuple[float, ...]


def _drain(fd: int, wait: float) -> bytes | None:
    """What the terminal received within `wait` seconds; None once the app's side closed."""
    ready, _, _ = select.select([fd], [], [], wait)
    if not ready:
        return b""
    try:
        return os.read(fd, 65536) or None
    except OSError:  # EIO: the app's side of the terminal is closed
        return None


def time_to_first_frame() -> float:
    """One launch: seconds to the first frame."""
    import fcntl
    import pty
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", SIZE[1], SIZE[0], 0, 0))
    env = dict(os.environ, TERM="xterm-256color", COLUMNS=str(SIZE[0]), LINES=str(SIZE[1]))
    start = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "tui_gym"],
        stdin=slave, stdout=slave, stderr=slave, env=env, start_new_session=True,
    )
    os.close(slave)
    seen = b""
    first: float | None = None
    try:
        while first is None:
            if time.perf_counter() - start > TIMEOUT:
                raise TimeoutError("the app drew no frame")
            data = _drain(master, 0.05)
            if data is None or proc.poll() is not None:
                raise RuntimeError(f"the app exited before its first frame ({proc.poll()})")
            seen = seen[-64:] + data
            if FIRST_PAINT in seen:
                first = time.perf_counter() - start
        os.write(master, b"q")
        deadline = time.perf_counter() + TIMEOUT
        while proc.poll() is None and time.perf_counter() < deadline:
            if _drain(master, 0.05) is None:
                break  # keep reading, so the app never blocks on a full terminal
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        os.close(master)
    return first


def measure(repeats: int) -> StartupResult:
    """Median over `repeats` launches."""
    return StartupResult(tuple(time_to_first_frame() for _ in range(repeats)))
