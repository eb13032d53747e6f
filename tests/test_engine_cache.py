"""The compiled code's cache folder: one per version of the engine's and algorithms' sources,
shared by a process and the processes it starts."""

from __future__ import annotations

from pathlib import Path

from tui_gym.core.engine import jit


def test_a_child_process_uses_the_folder_its_parent_chose(tmp_path: Path) -> None:
    chosen = jit.cache_folder({"NUMBA_CACHE_DIR": str(tmp_path)})
    assert chosen.parent == tmp_path and chosen.name == f"numba-{jit.sources_hash()}"
    # start() hands the chosen folder on in NUMBA_CACHE_DIR: a child finds the same one.
    assert jit.cache_folder({"NUMBA_CACHE_DIR": str(chosen)}) == chosen


def test_a_process_compiles_only_while_no_other_does(tmp_path: Path) -> None:
    """Processes compiling into one folder take turns (Numba could file two algorithms'
    loops under one name when two processes save at once): a process that must compile
    (or load what another compiled) waits on the folder's lock, then runs. The folder is
    a copy of this process's, so the child loads rather than compiles once it runs."""
    import fcntl
    import os
    import shutil
    import subprocess
    import sys
    import time

    from tui_gym.algorithms import Sarsa
    from tui_gym.core.engine import loop

    script = ("from tui_gym.algorithms import Sarsa\n"
              "from tui_gym.core.engine import loop\n"
              "x = Sarsa(2, n_states=2)\n"
              "loop.warm([(x.name, x.arrays(), x.compiled_params())])\n"
              "print('compiled')\n")
    x = Sarsa(2, n_states=2)
    loop.warm([(x.name, x.arrays(), x.compiled_params())])  # here, in the shared folder
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    folder = jit.cache_folder(env)
    shutil.copytree(jit.folder(), folder, ignore=shutil.ignore_patterns(".compile.lock", "warm-*"))
    with open(folder / ".compile.lock", "a") as held:
        fcntl.lockf(held, fcntl.LOCK_EX)
        child = subprocess.Popen([sys.executable, "-c", script], env=env, text=True,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            deadline = time.monotonic() + 120
            while not _waits_on_a_lock(child.pid):
                assert child.poll() is None, child.communicate()
                assert time.monotonic() < deadline, "the child never waited on the lock"
                time.sleep(0.05)
        except BaseException:
            child.kill()
            raise
    out, err = child.communicate(timeout=300)
    assert child.returncode == 0 and out.strip() == "compiled", err


def _waits_on_a_lock(pid: int) -> bool:
    """Whether process `pid` is blocked on a file lock (/proc/locks marks a waiter "->")."""
    with open("/proc/locks") as locks:
        return any("->" in line and f" {pid} " in line for line in locks)
