"""A program run in a process group of its own, ended whole on every way out: `start_group`."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
from typing import Any

# The watcher: reads the group's id, then waits for its input to close. "done" first
# means the parent ended the group itself; anything else, that the parent is gone.
_WATCHER = """
import os, signal, time
for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM):
    signal.signal(s, signal.SIG_IGN)
said = b""
try:
    while chunk := os.read(0, 64):
        said += chunk
except OSError:
    pass
words = said.split()
if words and words[-1] != b"done":
    pgid = int(words[0])
    for sig, wait in ((signal.SIGTERM, 1.0), (signal.SIGKILL, 0.0)):
        try:
            os.killpg(pgid, sig)
        except OSError:
            break
        end = time.monotonic() + wait
        while time.monotonic() < end:
            try:
                os.killpg(pgid, 0)
            except OSError:
                break
            time.sleep(0.02)
"""


class GroupProcess:
    """A started program (`process`, a `subprocess.Popen`) and the group it leads."""

    def __init__(self, process: subprocess.Popen[bytes], watcher: subprocess.Popen[bytes]):
        self.process = process
        self.pgid = process.pid  # a new session's leader leads its process group
        self._watcher: subprocess.Popen[bytes] | None = watcher
        assert watcher.stdin is not None
        with contextlib.suppress(OSError):
            watcher.stdin.write(f"{self.pgid}\n".encode())
            watcher.stdin.flush()

    def end(self, grace: float) -> int | None:
        """Close the program's input, give it `grace` s to exit, then kill what is left of
        its group; its exit code (None when it had to be killed)."""
        process = self.process
        if process.stdin is not None:
            with contextlib.suppress(OSError):
                process.stdin.close()
        code: int | None = None
        if grace > 0:
            with contextlib.suppress(subprocess.TimeoutExpired):
                code = process.wait(timeout=grace)
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pgid, signal.SIGKILL)  # what is left of its group
        process.wait()
        watcher, self._watcher = self._watcher, None
        if watcher is not None and watcher.stdin is not None:  # released once
            with contextlib.suppress(OSError):
                watcher.stdin.write(b" done\n")
                watcher.stdin.close()
            try:
                watcher.wait(timeout=5)
            except subprocess.TimeoutExpired:
                watcher.kill()
                watcher.wait()
        return code


def start_group(argv: list[str], **popen: Any) -> GroupProcess:
    """Start `argv` as the leader of a new session (OSError when it cannot start), watched
    so that its group ends even when this process is killed outright."""
    watcher = subprocess.Popen(
        [sys.executable, "-S", "-c", _WATCHER], stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
    )
    try:
        process = subprocess.Popen(argv, start_new_session=True, **popen)
    except BaseException:
        with contextlib.suppress(OSError):
            if watcher.stdin is not None:
                watcher.stdin.close()  # no group id said: it exits without killing
        watcher.wait()
        raise
    return GroupProcess(process, watcher)
