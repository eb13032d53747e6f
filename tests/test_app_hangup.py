"""The app ends when nobody is left to see it: its terminal closed (a terminal window shut,
`tmux kill-server`), or the pipes of an app `tui-gym serve` started closed (its server
gone). Real processes; every wait polls a condition with a deadline."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .terminal import DEADLINE, Terminal, console_script, descendants, ended


def wait_ended(process: subprocess.Popen[bytes], what: str) -> None:
    deadline = time.monotonic() + DEADLINE
    while process.poll() is None:
        if time.monotonic() > deadline:
            process.kill()
            raise AssertionError(f"{what}: the app was still running {DEADLINE:.0f} s later")
        time.sleep(0.02)  # polling a condition: the app runs on its own


@pytest.mark.parametrize("hangup_signal", [False, True],
                         ids=["closed", "closed-then-SIGHUP-and-SIGCONT"])
def test_the_app_ends_when_its_terminal_closes(tmp_path: Path, hangup_signal: bool) -> None:
    term = Terminal([console_script(), "--env", "gridworld", "--no-history"],
                    {"TUI_GYM_LOG_DIR": str(tmp_path / "logs")})
    try:
        term.wait_for_text("tui-gym")  # the header: the app is up
        term.type("t")
        term.wait_for_text("Hyperparameters")
        term.type("-")  # animated: training still runs when the terminal goes
        term.type(" ")
        term.wait_for_text("running")
        trainers = descendants(term.process.pid)
        term.hang_up()
        if hangup_signal:  # as a terminal that closes signals its processes
            os.killpg(term.process.pid, signal.SIGHUP)
            os.killpg(term.process.pid, signal.SIGCONT)
        wait_ended(term.process, "terminal closed")
    finally:
        term.close()
    assert term.process.returncode == 128 + signal.SIGHUP
    deadline = time.monotonic() + DEADLINE
    while not all(ended(pid) for pid in trainers):
        assert time.monotonic() < deadline, "the training process outlived the app"
        time.sleep(0.02)
    assert not (tmp_path / "logs").exists(), "a closed terminal is no crash"


def test_a_served_app_ends_when_its_pipes_close(tmp_path: Path) -> None:
    env = {**os.environ, "TEXTUAL_DRIVER": "textual.drivers.web_driver:WebDriver",
           "COLUMNS": "120", "ROWS": "40", "TUI_GYM_LOG_DIR": str(tmp_path / "logs")}
    process = subprocess.Popen(
        # Nothing trains here: the thread runner, so no training process starts at all.
        [sys.executable, "-m", "tui_gym", "--env", "blackjack", "--no-history", "--runner",
         "thread"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env,
        start_new_session=True,
    )
    assert process.stdin is not None and process.stdout is not None
    try:
        seen = b""
        deadline = time.monotonic() + DEADLINE
        while b"tui-gym" not in seen:  # the app's first frame, through the web driver
            assert time.monotonic() < deadline, "the served app drew nothing"
            seen = seen[-256:] + os.read(process.stdout.fileno(), 65536)
        process.stdin.close()  # the server is gone: nobody writes to the app or reads it
        process.stdout.close()
        wait_ended(process, "pipes closed")
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.returncode == 128 + signal.SIGHUP
    assert not (tmp_path / "logs").exists(), "closed pipes are no crash"
