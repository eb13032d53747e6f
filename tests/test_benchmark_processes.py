"""A benchmark's player program runs in a process group of its own, ended whole however the
benchmark ends: after the last episode (children it forked included), on SIGTERM or SIGHUP,
and when the benchmark is killed outright (kill -9). Real processes, real signals; every
wait is bounded and ends on the condition it waits for."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tui_gym.benchmark.players import ProcessPlayer
from tui_gym.benchmark.results import run_benchmark

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "heuristic_player.py"
WAIT_SECONDS = 60  # generous: the machine may be busy

# A wrapper script: a `sleep` in the background and a program that never reads its input
# nor writes a request, each writing its pid where the test finds it.
WRAPPER = """\
sleep 300 &
echo $! > "$1/sleep.pid"
echo $$ > "$1/shell.pid"
"{python}" -c 'import os, sys, time
open(sys.argv[1] + "/hang.tmp", "w").write(str(os.getpid()))
os.rename(sys.argv[1] + "/hang.tmp", sys.argv[1] + "/hang.pid")
time.sleep(300)' "$1"
"""

# A player that plays (the example heuristic) after forking a child that stays behind.
FORKER = """\
sleep 300 &
echo $! > "$1/sleep.pid"
exec "{python}" "{example}"
"""


def _wait_until(condition: object, what: str) -> None:
    deadline = time.monotonic() + WAIT_SECONDS
    while not condition():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def _alive(pid: int) -> bool:
    """Running (a zombie, waiting for a parent to reap it, is not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_bytes()
    except FileNotFoundError:
        return False
    return stat.rsplit(b") ", 1)[1][:1] != b"Z"


def _pids(folder: Path, *names: str) -> list[int]:
    _wait_until(lambda: all((folder / f"{n}.pid").exists() for n in names), "the pid files")
    return [int((folder / f"{n}.pid").read_text()) for n in names]


@pytest.fixture
def leftovers() -> Iterator[list[int]]:
    """Pids the test started indirectly: killed at the end if a test left any."""
    pids: list[int] = []
    yield pids
    for pid in pids:
        if _alive(pid):
            os.kill(pid, signal.SIGKILL)


def _script(folder: Path, text: str) -> Path:
    path = folder / "agent.sh"
    path.write_text(text.format(python=sys.executable, example=EXAMPLE))
    return path


def test_children_a_player_forked_end_with_the_benchmark(
    tmp_path: Path, leftovers: list[int]
) -> None:
    script = _script(tmp_path, FORKER)
    result = run_benchmark("blackjack", ProcessPlayer(f"sh {script} {tmp_path}"), episodes=3,
                           seed=0, decision_timeout=30)
    assert result.episodes == 3 and result.status.startswith("played every episode")
    [child] = _pids(tmp_path, "sleep")
    leftovers.append(child)
    _wait_until(lambda: not _alive(child), "the forked child to end")


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL])
def test_every_process_of_a_hung_player_ends_when_the_benchmark_is_ended(
    how: signal.Signals, tmp_path: Path, leftovers: list[int]
) -> None:
    script = _script(tmp_path, WRAPPER)
    benchmark = subprocess.Popen(
        [sys.executable, "-m", "tui_gym", "benchmark", "blackjack", "--agent-cmd",
         f"sh {script} {tmp_path}", "--episodes", "2", "--no-record",
         "--decision-timeout", "120"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        pids = _pids(tmp_path, "shell", "sleep", "hang")
        leftovers.extend(pids)
        assert all(map(_alive, pids))
        benchmark.send_signal(how)
        code = benchmark.wait(timeout=WAIT_SECONDS)
        assert code == (-signal.SIGKILL if how == signal.SIGKILL else 128 + how)
        for pid in pids:
            _wait_until(lambda pid=pid: not _alive(pid), f"process {pid} to end")
    finally:
        if benchmark.poll() is None:
            benchmark.kill()
            benchmark.wait()
    assert b"Traceback" not in (benchmark.stderr.read() if benchmark.stderr else b"")
