"""The command does its linear algebra on one BLAS thread unless the user chose otherwise."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import threadpoolctl

from tui_gym.cli.main import one_blas_thread

PROBE = """
import json, os
from threadpoolctl import threadpool_info
from tui_gym.cli import main
main(["envs", "--json"])
blas = [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]
print(json.dumps({"blas": blas, "env": os.environ.get("OPENBLAS_NUM_THREADS")}))
"""


def test_the_command_and_its_children_use_one_blas_thread() -> None:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                          text=True, timeout=120, check=True)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["blas"] and set(found["blas"]) == {1}
    assert found["env"] == "1"  # what the processes it starts read


def test_a_users_own_setting_is_kept(monkeypatch) -> None:
    def refuse(*args, **kwargs):
        raise AssertionError("the user's OPENBLAS_NUM_THREADS was overridden")

    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    monkeypatch.setattr(threadpoolctl, "threadpool_limits", refuse)
    one_blas_thread()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "3"
