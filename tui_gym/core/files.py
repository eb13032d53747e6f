"""Files a user names: read when regular and small, checked before writing, written atomically."""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import signal
import stat
import time
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = [
    "OutputPathError", "check_output_path", "read_regular_file", "remove_stale_temp_files",
    "write_atomically",
]

_STALE_AFTER = 60.0  # seconds: a temporary file without a writer's pid this old is left over


class OutputPathError(ValueError):
    """A path a file cannot be written to; the message names it and says why."""


_FILE_KINDS = (
    (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device"),
    (stat.S_ISSOCK, "a socket"),
)


def read_regular_file(
    path: Path, limit: int, noun: str, fail: Callable[[str], Exception],
    too_big: Callable[[int | None], str],
) -> bytes:
    """The bytes of the regular file `path` of at most `limit` bytes, pipes and devices refused
    unread; a refusal raises `fail(why)`, `why` naming what it is not (`noun`) or
    `too_big(size)` (None: more than `limit` bytes came while reading)."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise fail("no such file") from None
    except IsADirectoryError:
        raise fail(f"is a folder, not {noun}") from None
    except OSError as exc:
        raise fail(f"cannot read ({exc.strerror or exc})") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise fail(f"is a folder, not {noun}")
        if not stat.S_ISREG(info.st_mode):
            kind = next((name for test, name in _FILE_KINDS if test(info.st_mode)), "not a file")
            raise fail(f"is {kind}, not {noun}")
        if info.st_size > limit:
            raise fail(too_big(info.st_size))
        chunks = []
        total = 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise fail(too_big(None))
        return b"".join(chunks)
    except OSError as exc:
        raise fail(f"cannot read ({exc.strerror or exc})") from None
    finally:
        os.close(fd)


def _real_target(path: Path) -> Path:
    """Where writing `path` lands: through symbolic links to the file they name."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def check_output_path(path: str | Path) -> Path:
    """`path` as a `Path` when a file can be written there; else `OutputPathError`."""
    text = str(path)
    if not text.strip():
        raise OutputPathError("the path is empty: give a file name")
    given = Path(path).expanduser()
    if text.endswith(os.sep):
        raise OutputPathError(f"{given}: a file name is needed, not a folder")
    target = _real_target(given)
    folder = target.parent
    try:
        folder_stat = folder.stat()
    except FileNotFoundError:
        raise OutputPathError(f"{given}: the folder {folder} does not exist") from None
    except OSError as exc:
        raise OutputPathError(f"{given}: cannot use the folder {folder} ({exc.strerror})") from None
    if not stat.S_ISDIR(folder_stat.st_mode):
        raise OutputPathError(f"{given}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputPathError(f"{given}: the folder {folder} is not writable")
    try:
        mode = target.stat().st_mode
    except FileNotFoundError:
        return given
    except OSError as exc:
        raise OutputPathError(f"{given}: cannot use this path ({exc.strerror})") from None
    if stat.S_ISDIR(mode):
        raise OutputPathError(f"{given}: is a folder; give a file name")
    if not stat.S_ISREG(mode):
        raise OutputPathError(f"{given}: is not a regular file; will not write over it")
    return given


def write_atomically(path: str | Path, data: bytes | str) -> Path:
    """Write `data` (text as UTF-8) to `path` through a temporary file, fsync and a rename;
    `OutputPathError` when it cannot be written there, OSError when the write fails."""
    given = check_output_path(path)
    payload = data.encode("utf-8") if isinstance(data, str) else data
    target = _real_target(given)
    folder = target.parent if str(target.parent) else Path(".")
    remove_stale_temp_files(target)
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        mode = None
    with _signals_deferred():
        tmp, fd = _create_temp(folder, target.name)
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(payload)
                fh.flush()
                if mode is not None:
                    os.fchmod(fh.fileno(), mode)
                os.fsync(fh.fileno())
            os.replace(tmp, target)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
    _fsync_folder(folder)
    return given


def pid_alive(pid: int) -> bool:
    """Whether process `pid` may be alive (someone else's process, or no pid at all: yes)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True  # someone else's process, or not a pid at all: leave its file alone
    return True


def remove_stale_temp_files(path: Path) -> None:
    """Remove our temporary files a killed writer left beside `path` (pid gone, or old)."""
    # `.NAME.PID.HEX.tmp` (ours) and `.NAME.XXXXXXXX.tmp` (from tempfile, by earlier versions).
    pattern = re.compile(rf"\.{re.escape(path.name)}\.(?:(\d+)\.[0-9a-f]+|[a-z0-9_]{{8}})\.tmp")
    folder = path.parent if str(path.parent) else Path(".")
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    now = time.time()
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None:
            continue
        try:
            info = entry.stat(follow_symlinks=False)
            if not stat.S_ISREG(info.st_mode):
                continue
            pid = match.group(1)
            stale = not pid_alive(int(pid)) if pid else now - info.st_mtime > _STALE_AFTER
            if stale:
                os.unlink(entry.path)
        except OSError:
            continue


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold SIGTERM, SIGHUP and SIGINT (those with their default action, on the main thread)
    until the block is done, so a signal never leaves a temporary file behind."""
    from tui_gym.core.engine.processes import handling  # signals, threads: not for every read

    caught: list[int] = []
    try:
        with handling(("SIGTERM", "SIGHUP", "SIGINT"), lambda signum, frame: caught.append(signum),
                      untouched=True):
            yield
    finally:
        for sig in dict.fromkeys(caught):
            signal.raise_signal(sig)


def _create_temp(folder: Path, name: str) -> tuple[Path, int]:
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    while True:
        tmp = folder / f".{name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"
        try:
            return tmp, os.open(tmp, flags, 0o666)  # the umask applies, as for any new file
        except FileExistsError:
            continue


def _fsync_folder(folder: Path) -> None:
    """Make the rename itself durable (where the platform allows it)."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
