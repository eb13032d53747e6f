"""`LineWriter`: appends whole lines to a file, each one flushed to the OS as it is written.

Each line goes to the file in a single `write` on a descriptor opened for
appending, so a crash (or a kill) of the program leaves every line written
before it whole and no part of the next one. A write the disk cuts short
(full, quota) is taken back: the file is truncated to where the line began
and the error raised, so the file never ends in half a line written here
(a pipe cannot be taken back: its reader sees a broken last line).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path


class LineWriter:
    """Appends lines (bytes ending in a newline) to `path`; `truncate` empties it first."""

    def __init__(self, path: str | Path, *, truncate: bool = True) -> None:
        self.path = Path(path)
        flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | getattr(os, "O_CLOEXEC", 0)
        if truncate:
            flags |= os.O_TRUNC
        self._fd: int | None = os.open(self.path, flags, 0o644)
        self.lines = 0

    @property
    def closed(self) -> bool:
        return self._fd is None

    def write(self, line: bytes) -> None:
        """Write one whole line; OSError (and nothing of the line in the file) when it fails."""
        if self._fd is None:
            raise ValueError("the recording is closed")
        if not line.endswith(b"\n") or b"\n" in line[:-1]:
            raise ValueError("a line must end in its only newline")
        fd = self._fd
        try:
            start: int | None = os.lseek(fd, 0, os.SEEK_END)
        except OSError:  # a pipe: nothing to take back
            start = None
        try:
            written = self._raw_write(fd, line)
            while written < len(line):  # a short write: finish it or fail
                more = self._raw_write(fd, line[written:])
                if more <= 0:
                    raise OSError(f"{self.path}: the line could not be written whole")
                written += more
        except OSError:
            if start is not None:
                with contextlib.suppress(OSError):
                    os.ftruncate(fd, start)
            raise
        self.lines += 1

    @staticmethod
    def _raw_write(fd: int, data: bytes) -> int:
        return os.write(fd, data)

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)
