"""Programs in a pseudo-terminal, as a person runs them: `Terminal` launches one and keeps
everything it writes; `console_script()` is the installed `tui-gym`."""

from __future__ import annotations

import contextlib
import fcntl
import os
import select
import shutil
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

DEADLINE = 20.0  # seconds; generous for a loaded machine, never reached when things work


class Terminal:
    """A program in a pseudo-terminal of 120×40, with everything it writes kept."""

    def __init__(self, argv: list[str], env: dict[str, str]) -> None:
        master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
        # The terminal's size is the pseudo-terminal's, not one left in the environment.
        inherited = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES")}
        self.process = subprocess.Popen(
            argv, stdin=slave, stdout=slave, stderr=slave, start_new_session=True,
            env={**inherited, "TERM": "xterm-256color", **env},
        )
        os.close(slave)
        self.master = master
        self.output = bytearray()
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                ready, _, _ = select.select([self.master], [], [], 0.05)
            except (OSError, ValueError):  # the terminal was closed (`hang_up`)
                return
            if not ready:
                if self.process.poll() is not None:
                    return
                continue
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            with self._lock:
                self.output.extend(data)

    @property
    def text(self) -> str:
        with self._lock:
            return self.output.decode("utf-8", "replace")

    def wait_for(self, predicate: Callable[[], bool], what: str) -> None:
        deadline = time.monotonic() + DEADLINE
        while not predicate():
            if time.monotonic() > deadline:
                self.kill()
                raise AssertionError(f"timed out waiting for {what}; the screen ended:\n"
                                     f"{self.text[-2000:]}")
            time.sleep(0.02)  # polling a condition: the program runs on its own

    def wait_for_text(self, words: str) -> None:
        self.wait_for(lambda: words in self.text, repr(words))

    def type(self, keys: str) -> None:
        os.write(self.master, keys.encode())

    def after(self, seconds: float) -> None:
        """Let the program run this long (it trains meanwhile)."""
        until = time.monotonic() + seconds
        self.wait_for(lambda: time.monotonic() >= until or self.process.poll() is not None,
                      f"{seconds} s to pass")

    def exit_code(self) -> int:
        try:
            code = self.process.wait(timeout=DEADLINE)
        except subprocess.TimeoutExpired:
            self.kill()
            raise AssertionError(f"did not end; the screen ended:\n{self.text[-2000:]}") from None
        self._reader.join(timeout=5)
        return code

    def kill(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signal.SIGKILL)

    def hang_up(self) -> None:
        """Close the terminal under the program, as a terminal window closing does."""
        master, self.master = self.master, -1
        os.close(master)
        self._reader.join(timeout=5)

    def close(self) -> None:
        if self.process.poll() is None:
            self.kill()
            self.process.wait()
        if self.master >= 0:
            with contextlib.suppress(OSError):
                os.close(self.master)


def descendants(pid: int) -> list[int]:
    """Every process below `pid`: the children of any of its threads, theirs, and so on."""
    found: list[int] = []
    for path in Path(f"/proc/{pid}/task").glob("*/children"):
        with contextlib.suppress(OSError):
            for child in map(int, path.read_text().split()):
                found += [child, *descendants(child)]
    return found


def ended(pid: int) -> bool:
    """Whether a process has ended (gone, or a zombie waiting for whoever adopted it)."""
    try:
        return "zombie" in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True


def console_script() -> str:
    found = shutil.which("tui-gym", path=str(Path(sys.executable).parent))
    if found is None:
        pytest.skip("the tui-gym console script is not installed beside this Python")
    return found
