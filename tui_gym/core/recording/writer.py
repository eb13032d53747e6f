"""`LineWriter`: appends whole lines to a file, each one flushed to the OS as it is written."""

from __future__ import annotations

import contextlib
import errno
import os
import stat
from pathlib import Path


class LineWriter:
    """Appends lines (bytes ending in a newline) to `path`; `truncate` empties it first."""

    def __init__(self, path: str | Path, *, truncate: bool = True) -> None:
        self.path = Path(path)
        # Opened without blocking (a pipe with no reader must not hang) and emptied only
        # once it is known to be a regular file: a device or a pipe is never written.
        flags = (os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_NONBLOCK
                 | getattr(os, "O_CLOEXEC", 0))
        refused = OSError(errno.EINVAL, "is not a regular file; will not write over it")
        try:
            fd = os.open(self.path, flags, 0o644)
        except OSError as error:
            if error.errno == errno.ENXIO:  # a pipe no one reads
                raise refused from None
            raise
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                raise refused
            os.set_blocking(fd, True)
            if truncate:
                os.ftruncate(fd, 0)
        except BaseException:
            os.close(fd)
            raise
        self._fd: int | None = fd

    def write(self, line: bytes) -> None:
        """Write one whole line; OSError (and nothing of the line in the file) when it fails."""
        if self._fd is None:
            raise ValueError("the recording is closed")
        if not line.endswith(b"\n") or b"\n" in line[:-1]:
            raise ValueError("a line must end in its only newline")
        fd = self._fd
        start = os.lseek(fd, 0, os.SEEK_END)
        written = 0
        try:
            while written < len(line):  # a short write: finish it or fail
                more = self._raw_write(fd, line[written:])
                if more <= 0:
                    raise OSError(f"{self.path}: the line could not be written whole")
                written += more
        except OSError:
            with contextlib.suppress(OSError):
                os.ftruncate(fd, start)
            raise

    @staticmethod
    def _raw_write(fd: int, data: bytes) -> int:
        return os.write(fd, data)

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)
