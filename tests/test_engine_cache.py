"""The compiled code's cache folder: one per version of the engine's and algorithms' sources,
shared by a process and the processes it starts."""

from __future__ import annotations

import subprocess
from pathlib import Path

from tui_gym.core.engine import jit


def test_a_child_process_uses_the_folder_its_parent_chose(tmp_path: Path) -> None:
    chosen = jit.cache_folder({"NUMBA_CACHE_DIR": str(tmp_path)})
    assert chosen.parent == tmp_path and chosen.name == f"numba-{jit.sources_hash()}"
    # start() hands the chosen folder on in NUMBA_CACHE_DIR: a child finds the same one.
    assert jit.cache_folder({"NUMBA_CACHE_DIR": str(chosen)}) == chosen


# A child: sets up learners and a seeded model, says "ready", waits for a line, then
# trains each learner (compiling or loading its loop, saying "compiling" as the loop's
# compile starts) and prints its values, and how many functions it compiled.
_CHILD = """
import sys
import numpy as np
from tui_gym.algorithms import QLearning, Sarsa
from tui_gym.core.engine import jit, loop, rules
from tui_gym.core.mdp.model import FiniteMDP
jit.start()
from numba.core import event
compiled = []
class Said(event.Listener):
    def on_start(self, ev):
        compiled.append(ev)
        if ev.data["dispatcher"].py_func.__name__ == "run_model":
            print("compiling", flush=True)
    def on_end(self, ev):
        pass
draw = np.random.default_rng(7)
shape = (5, 3, 2)
prob = draw.random(shape)
prob /= prob.sum(-1, keepdims=True)
model = loop.ModelArrays.of(FiniteMDP(draw.integers(0, 5, shape), prob, draw.normal(size=shape),
                                      draw.random(shape) < 0.2, np.full(5, 0.2)))
kinds = {"sarsa": Sarsa, "q-learning": QLearning}
learners = [kinds[name](3, n_states=5, seed=3) for name in sys.argv[1:]]
event.register("numba:compile", Said())
print("ready", flush=True)
sys.stdin.readline()
for x in learners:
    loop.play(x, model, loop.Cursor(), 40, 10**6, np.zeros((40, loop.COLUMNS)), rules.new_log())
    print(x.name, x.arrays()[0].tolist(), flush=True)
print("compiled", len(compiled))
"""


def test_two_processes_compile_learners_at_once_and_each_loads_what_the_other_saved(
        tmp_path: Path) -> None:
    """Two processes compile two learners' loops into one folder at once, taking turns
    only to file what they compiled (each waits on the folder's lock to save, after it
    started compiling); a third loads both, compiling nothing, and each learns what it
    learned in the process that compiled it (Numba numbers a function's entries by
    counting its index: saved at once, one's code could be filed under the other's
    name). The folder is a copy of this process's without the loops."""
    import fcntl
    import os
    import shutil
    import subprocess
    import sys
    import time

    from tui_gym.algorithms import QLearning, Sarsa
    from tui_gym.core.engine import loop

    learners = [cls(3, n_states=5) for cls in (Sarsa, QLearning)]
    loop.warm([(x.name, x.arrays(), x.compiled_params()) for x in learners])  # in the shared folder
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    folder = jit.cache_folder(env)
    shutil.copytree(jit.folder(), folder,
                    ignore=shutil.ignore_patterns(".compile.lock", "warm-*", "loop.run_model-*"))

    def child(*names: str) -> subprocess.Popen[str]:
        return subprocess.Popen([sys.executable, "-c", _CHILD, *names], env=env, text=True,
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE)

    children = [child("sarsa"), child("q-learning")]
    try:
        for each in children:
            assert _line(each) == "ready"
        with open(folder / ".compile.lock", "a") as held:
            fcntl.lockf(held, fcntl.LOCK_EX)
            for each in children:
                assert each.stdin is not None
                each.stdin.write("go\n")
                each.stdin.flush()
            for each in children:  # each starts compiling while the lock is held
                assert _line(each) == "compiling"
            deadline = time.monotonic() + 120
            while not all(_waits_on_a_lock(each.pid) for each in children):
                assert all(each.poll() is None for each in children)
                assert time.monotonic() < deadline, "a child never waited to save"
                time.sleep(0.05)
    except BaseException:
        for each in children:
            each.kill()
            each.communicate()
        raise
    learned = {}
    for each in children:
        out, err = each.communicate(timeout=300)
        assert each.returncode == 0, err
        name, values = out.splitlines()[0].split(" ", 1)
        learned[name] = values
    out, err = child("sarsa", "q-learning").communicate("go\n", timeout=300)
    lines = out.splitlines()
    assert lines[0] == "ready" and lines[-1] == "compiled 0", err
    assert dict(line.split(" ", 1) for line in lines[1:-1]) == learned
    assert learned["sarsa"] != learned["q-learning"]


def _line(process: subprocess.Popen[str], seconds: float = 120.0) -> str:
    """The next line `process` prints, waiting at most `seconds` for it."""
    import select

    assert process.stdout is not None
    ready, _, _ = select.select([process.stdout], [], [], seconds)
    assert ready, f"no line within {seconds} s"
    return process.stdout.readline().strip()


def _waits_on_a_lock(pid: int) -> bool:
    """Whether process `pid` is blocked on a file lock (/proc/locks marks a waiter "->")."""
    with open("/proc/locks") as locks:
        return any("->" in line and f" {pid} " in line for line in locks)


def test_a_learners_calls_from_python_compile_nothing_beyond_its_loop() -> None:
    """Learning, acting and the greedy choice from Python (the env loop, the `n` step) run
    the compiled rule, `act` and `greedy` the loop calls: a cold compile makes no
    separate forms of them."""
    from tui_gym.algorithms import Sarsa

    learner = Sarsa(3, n_states=5, seed=1)
    learner.learn(0, 1, 1.0, 2, False)
    learner.act(2)
    learner.greedy(3)
    if jit.compiles():
        compiled_apart = {getattr(fn, "__name__", "") for fn, *_ in jit._ENTRIES}
        assert compiled_apart <= {"run_model", "run_scored"}


def test_the_engine_prepares_where_numba_has_no_cpu_target_to_set_up(monkeypatch) -> None:
    """`prepare` (a fork server's) without Numba's CPU target where it looks: it starts the
    engine only, and a child sets the target up as it loads its learner."""
    from numba.core import registry

    monkeypatch.delattr(registry, "cpu_target")
    jit.prepare()
    assert jit.folder().is_dir()
