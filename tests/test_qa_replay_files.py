"""`tui-gym replay` on a file that is not a regular one: refused at once, never waited on
nor read through."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import pytest

from tui_gym.core.recording import RecordingError, read_recording

PATIENCE = 30.0  # seconds; a refusal takes milliseconds


def read_on_a_thread(path: Path) -> tuple[threading.Thread, list[object]]:
    """`read_recording(path)` on a daemon thread, joined for up to PATIENCE seconds."""
    outcome: list[object] = []

    def read() -> None:
        try:
            outcome.append(read_recording(path))
        except Exception as exc:  # noqa: BLE001 - the test reads what it was
            outcome.append(exc)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(timeout=PATIENCE)
    return reader, outcome


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_named_pipe_with_no_writer_is_refused_not_waited_on(tmp_path) -> None:
    pipe = tmp_path / "games.jsonl"
    os.mkfifo(pipe)
    reader, outcome = read_on_a_thread(pipe)
    if reader.is_alive():  # it waits for a writer: give it one (at end of file) and fail
        os.close(os.open(pipe, os.O_WRONLY | os.O_NONBLOCK))
        reader.join(timeout=PATIENCE)
        pytest.fail("read_recording waited on a named pipe")
    assert isinstance(outcome[0], RecordingError)
    assert "not a regular file" in str(outcome[0])


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_a_device_is_refused_without_reading_it() -> None:
    reader, outcome = read_on_a_thread(Path("/dev/zero"))
    assert not reader.is_alive(), "read_recording reads through /dev/zero"
    assert isinstance(outcome[0], RecordingError)
    assert "/dev/zero is not a regular file" in str(outcome[0])
