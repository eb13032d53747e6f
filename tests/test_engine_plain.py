"""With `NUMBA_DISABLE_JIT=1` every kernel runs as plain Python: the smallest game's contract
still holds (training to its bound included), so coverage and a debugger see the engine."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_smallest_games_contract_holds_with_the_kernels_as_plain_python() -> None:
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    env.pop("PYTEST_XDIST_WORKER", None)
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider",
         "tests/test_games_contract.py", "-k", "frozenlake"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600, check=False,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert " passed" in done.stdout and "failed" not in done.stdout
