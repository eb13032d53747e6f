"""Shared pytest setup: the `slow` marker, run only when TUI_GYM_SLOW=1; one BLAS thread
per process; bytecode kept for the processes the tests start; one compiled-code cache for
every process, filled once before the workers start; the pilot's waits asked of the busy
widgets only, its idle checks over short windows; one xdist worker more than CPUs; long
modules first; every run's history in a file of its own."""

from __future__ import annotations

import gc
import inspect
import os
import sys
from pathlib import Path

import pytest

SLOW_ENV = "TUI_GYM_SLOW"
GC_THRESHOLDS = (20_000, 20, 100)  # young, middle and full generations
NUMBA_CACHE = Path(__file__).resolve().parent.parent / ".pytest_cache" / "numba"


def _one_blas_thread() -> None:
    """Every process of the run does its linear algebra on one thread. The exact values'
    solves are small, and the workers, the apps and their children already share the
    cores: OpenBLAS's extra threads spun on them, waiting for work, and cost more CPU
    than the solves. Set before numpy loads here, and inherited by every process the
    tests start."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


_one_blas_thread()


def _write_bytecode() -> None:
    """Where writing bytecode is switched off, switch it on for the run. The xdist workers,
    the `python -m tui_gym` subprocesses and the training processes all start from this
    environment: without bytecode each compiles the package and rewrites the test modules
    afresh. Python then reads the installed packages' own bytecode and writes the
    project's into its `__pycache__` folders, which git ignores (not a prefix folder:
    Python would read no installed package's bytecode there, and every process would
    compile them all again). This runs when pytest loads this file, before the workers
    start."""
    if not os.environ.get("PYTHONDONTWRITEBYTECODE") or os.environ.get("PYTHONPYCACHEPREFIX"):
        return
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    sys.dont_write_bytecode = False


_write_bytecode()


def _share_compiled_code() -> None:
    """Every process of the run (the workers, the app's and the comparisons' children)
    loads compiled code from one folder (the engine keys it by its sources)."""
    os.environ.setdefault("NUMBA_CACHE_DIR", str(NUMBA_CACHE))


_share_compiled_code()


COMPILING = "TUI_GYM_TESTS_COMPILED"  # the file the compiling process writes when it ends
COMPILING_WAIT = 600.0  # seconds a worker waits at most for it
WARM_ALL = """
import sys
try:
    from tui_gym.algorithms import ALGORITHMS
    from tui_gym.core.engine import loop
    learners = [cls(2, n_states=2) for cls in ALGORITHMS]
    loop.warm([(x.name, x.arrays(), x.compiled_params()) for x in learners])
finally:
    open(sys.argv[1], "w").close()
"""


def _compile_once(config: pytest.Config) -> None:
    """With workers, compile every learner first (`loop.warm`: in processes, one per core),
    so no two workers compile the same code at once (a second run finds it all in the
    cache). The compiling runs beside the workers' start and collection; each worker waits
    for it before its first test (`_wait_for_compiling`)."""
    if os.environ.get("PYTEST_XDIST_WORKER") or not getattr(config.option, "numprocesses", 0):
        return
    if os.environ.get("NUMBA_DISABLE_JIT"):
        return
    import subprocess
    import tempfile

    done = Path(tempfile.mkdtemp(prefix="tui-gym-compiling-")) / "ended"
    config._tui_gym_compiling = subprocess.Popen(  # type: ignore[attr-defined]
        [sys.executable, "-c", WARM_ALL, str(done)], cwd=Path(__file__).resolve().parent.parent)
    os.environ[COMPILING] = str(done)


def _wait_for_compiling() -> None:
    """On a worker, wait until the controller's compiling process has ended (having filed
    every learner, or not: the tests then compile what they use)."""
    done = os.environ.get(COMPILING)
    if not os.environ.get("PYTEST_XDIST_WORKER") or not done:
        return
    import time

    deadline = time.monotonic() + COMPILING_WAIT
    while not Path(done).exists() and time.monotonic() < deadline:
        time.sleep(0.05)


def _pilot_waits_on_busy_widgets(config: pytest.Config) -> None:
    """In each process that runs tests, the pilot's wait after a key or a pause asks only
    the widgets with something to do, and looks for an idle process over short windows
    (`tests/pilot_waits.py`)."""
    if getattr(config.option, "numprocesses", 0) and not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    from tests.pilot_waits import wait_on_busy_widgets_only

    wait_on_busy_widgets_only()


def pytest_configure(config: pytest.Config) -> None:
    _compile_once(config)
    _pilot_waits_on_busy_widgets(config)
    config.addinivalue_line(
        "markers",
        f"slow: takes tens of seconds; skipped unless the environment variable {SLOW_ENV}=1",
    )


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """`-n auto` starts one worker more than there are CPUs: the app's tests spend part
    of their time waiting (on Textual's timers, on a training process), and the extra
    worker runs while another waits. PYTEST_XDIST_AUTO_NUM_WORKERS still decides first."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    return len(os.sched_getaffinity(0)) + 1


def _module_rank(items: list[pytest.Item]) -> int:
    """0 for a module whose tests share one worker (an xdist group), 1 for one with app
    tests (coroutines under the pilot), 2 for the rest."""
    if any(item.get_closest_marker("xdist_group") for item in items):
        return 0
    if any(inspect.iscoroutinefunction(getattr(item, "obj", None)) for item in items):
        return 1
    return 2


def _long_modules_first(items: list[pytest.Item]) -> None:
    """Order whole modules so the long units start first and the many short tests fill
    the tail: a group, or a pilot test of several seconds, dispatched last keeps one
    worker busy while the other has nothing left to do. Each module's tests stay
    together and in their order, so module fixtures are set up once."""
    modules: dict[str, list[pytest.Item]] = {}
    for item in items:
        modules.setdefault(item.nodeid.split("::", 1)[0], []).append(item)
    ordered = sorted(modules.values(), key=_module_rank)  # stable: file order within a rank
    items[:] = [item for module in ordered for item in module]


def _name_groups(config: pytest.Config, items: list[pytest.Item]) -> None:
    """On a worker under `--dist loadgroup`, end the node id of each test of an
    `xdist_group` with `@GROUP`, as xdist means to: the controller sends a group's tests to
    one worker by that suffix. xdist sets it where pytest 9 no longer reads a node id, and
    without it every worker ran a group's tests and started its module's servers."""
    if not getattr(config.option, "loadgroup", False):
        return
    for item in items:
        names = sorted({str(mark.args[0] if mark.args else mark.kwargs.get("name", "default"))
                        for mark in item.iter_markers("xdist_group")})
        suffix = "@" + "_".join(names)
        if names and not item.nodeid.endswith(suffix) and hasattr(item, "_id"):
            item._id = type(item._id).parse(item.nodeid + suffix)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    _name_groups(config, items)
    _long_modules_first(items)
    if os.environ.get(SLOW_ENV) == "1":
        return
    skip = pytest.mark.skip(reason=f"slow; set {SLOW_ENV}=1 to run")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def pytest_unconfigure(config: pytest.Config) -> None:
    """The compiling process is reaped and its folder removed."""
    compiling = getattr(config, "_tui_gym_compiling", None)
    if compiling is not None:
        compiling.wait()
        import shutil

        shutil.rmtree(Path(os.environ[COMPILING]).parent, ignore_errors=True)


def pytest_collection_finish(session: pytest.Session) -> None:
    """What the imports and the collected tests made lives until the run ends: frozen,
    the collector's passes no longer walk it. The collector also runs less often: a
    test process allocates in bursts (an app's frames) and frees nearly all of it."""
    _wait_for_compiling()
    gc.collect()
    gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)


def pytest_runtest_teardown(item: pytest.Item) -> None:
    """Let an app's drawing go with the app. Textual keeps the last 1,024 widgets'
    style caches (each with its lines) in an `lru_cache` keyed by the cache itself,
    so every app a test ran stayed alive for several tests after, and the collector
    walked all of it again and again."""
    styles_cache = sys.modules.get("textual._styles_cache")
    if styles_cache is not None:
        styles_cache.StylesCache.get_inner_outer.cache_clear()


@pytest.fixture(autouse=True, scope="session")
def _run_history_in_tmp(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every run the tests record goes to a file of their own, never the user's history."""
    os.environ["TUI_GYM_DB"] = str(tmp_path_factory.mktemp("history") / "runs.db")
