"""Shared pytest setup: the `slow` marker, run only when TUI_GYM_SLOW=1; one BLAS thread
per process; bytecode kept for the processes the tests start; one compiled-code cache for
every process, filled once before the workers start, and the tests collected once on a
fresh checkout; the pilot's waits asked of the busy widgets only, its idle checks over
short windows; each test's garbage collected as it ends; one xdist worker more than CPUs;
long modules first; every run's history in a file of its own."""

from __future__ import annotations

import gc
import inspect
import os
import sys
from pathlib import Path

import pytest

SLOW_ENV = "TUI_GYM_SLOW"
# Young, middle and full generations: a safety net; each test's garbage is collected at its end.
GC_THRESHOLDS = (200_000, 10, 1_000)
ROOT = Path(__file__).resolve().parent.parent
NUMBA_CACHE = ROOT / ".pytest_cache" / "numba"


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
COLLECTING = "TUI_GYM_TESTS_COLLECTED"  # and the collecting process
BEFORE_WAIT = 600.0  # seconds a worker waits at most for either
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
COLLECT = """
import sys
import pytest
try:
    pytest.main(["--collect-only", "-q", "-n", "0", "-p", "no:cacheprovider", *sys.argv[2:]])
finally:
    open(sys.argv[1], "w").close()
"""


def _before_workers(config: pytest.Config, name: str, code: str, *args: str) -> None:
    """In the controller, run `code` in a process of its own beside the workers' start; it
    writes a file when it ends, named in the environment variable `name` (the workers
    wait for it: `_wait_before`)."""
    import subprocess
    import tempfile

    done = Path(tempfile.mkdtemp(prefix="tui-gym-tests-")) / "ended"
    process = subprocess.Popen([sys.executable, "-c", code, str(done), *args], cwd=ROOT,
                               stdout=subprocess.DEVNULL)
    config._tui_gym_before.append((process, done))  # type: ignore[attr-defined]
    os.environ[name] = str(done)


def _wait_before(name: str) -> None:
    """On a worker, wait until the controller's process named by `name` has ended (having
    done its work, or not: the worker then does what it needs itself)."""
    done = os.environ.get(name)
    if not os.environ.get("PYTEST_XDIST_WORKER") or not done:
        return
    import time

    deadline = time.monotonic() + BEFORE_WAIT
    while not Path(done).exists() and time.monotonic() < deadline:
        time.sleep(0.05)


def _first_in_the_controller(config: pytest.Config) -> None:
    """With workers, two jobs are done once, before the workers need them, rather than by
    every worker at once. Compile every learner (`loop.warm`: in processes, one per core),
    so no two workers compile the same code (a second run finds it all in the cache); each
    worker waits for it before its first test. On a fresh checkout, collect the tests asked
    for: pytest rewrites each test module's asserts and files the result beside it, where
    each worker, waiting for it before collecting, reads it instead of rewriting them all."""
    if os.environ.get("PYTEST_XDIST_WORKER") or not getattr(config.option, "numprocesses", 0):
        return
    config._tui_gym_before = []  # type: ignore[attr-defined]
    if not os.environ.get("NUMBA_DISABLE_JIT"):
        _before_workers(config, COMPILING, WARM_ALL)
    if not any((Path(__file__).parent / "__pycache__").glob("test_*-pytest-*.pyc")):
        given = config.args_source == pytest.Config.ArgsSource.ARGS
        base = config.invocation_params.dir if given else config.rootpath
        _before_workers(config, COLLECTING, COLLECT, *(str(base / arg) for arg in config.args))


def _pilot_waits_on_busy_widgets(config: pytest.Config) -> None:
    """In each process that runs tests, the pilot's wait after a key or a pause asks only
    the widgets with something to do, and looks for an idle process over short windows
    (`tests/pilot_waits.py`)."""
    if getattr(config.option, "numprocesses", 0) and not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    from tests.pilot_waits import wait_on_busy_widgets_only

    wait_on_busy_widgets_only()


def pytest_configure(config: pytest.Config) -> None:
    _first_in_the_controller(config)
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
    """The processes run before the workers are reaped and their folders removed. The last
    test's garbage was collected as it ended: what is left lives until the process ends,
    frozen, so pytest's last collection (which looks for errors raised in finalizers) does
    not walk it all."""
    gc.freeze()
    import shutil

    for process, done in getattr(config, "_tui_gym_before", ()):
        process.wait()
        shutil.rmtree(done.parent, ignore_errors=True)


@pytest.hookimpl(tryfirst=True)
def pytest_collection(session: pytest.Session) -> None:
    """On a worker, collect once the controller's collecting process has ended."""
    _wait_before(COLLECTING)


def pytest_collection_finish(session: pytest.Session) -> None:
    """What the imports and the collected tests made lives until the run ends: frozen,
    the collector's passes no longer walk it. The collector runs on its own only after
    large bursts: each test's garbage is collected when it ends (`pytest_runtest_teardown`)."""
    _wait_before(COMPILING)
    gc.collect()
    gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item: pytest.Item) -> None:
    """After the test's fixtures are gone, collect its garbage, young: an app's widgets,
    messages and frames are cycles that die with the app. Collected mid-test, they were
    walked while alive, then promoted to where only a full collection reaches them.
    Textual keeps the last 1,024 widgets' style caches (each with its lines) in an
    `lru_cache` keyed by the cache itself: cleared first, so the app goes with its test."""
    styles_cache = sys.modules.get("textual._styles_cache")
    if styles_cache is not None:
        styles_cache.StylesCache.get_inner_outer.cache_clear()
    gc.collect(1)


@pytest.fixture(autouse=True, scope="session")
def _run_history_in_tmp(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Every run the tests record goes to a file of their own, never the user's history."""
    os.environ["TUI_GYM_DB"] = str(tmp_path_factory.mktemp("history") / "runs.db")
