"""`compare`'s figures: against the same learners one after another in the tutorial loop,
and the cost of running experiments as tasks (the task split, a Dask cluster's scheduler)."""

from __future__ import annotations

import logging
import math
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

from tui_gym.bench import tutorial
from tui_gym.bench.figures import timed

GAME = "cliffwalking"
ALGORITHMS = ("q-learning", "sarsa")
SETTINGS = {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5,
            "learning_rate_schedule": "constant"}
COMPARE_REPEATS = 3  # the comparison is short, so its time is the median of a few runs
SWEEP_RATES = ("0.1", "0.2", "0.4", "0.8")
CLUSTER_WORKERS = 2


@dataclass(frozen=True)
class SeedsSpeed:
    """`compare` against the tutorial loop on the same learners (seconds each), and the
    comparison's mean online return per algorithm over all its episodes."""

    game: str
    algorithms: tuple[str, ...]
    seeds: int
    episodes: int
    compare_s: float
    tutorial_s: float  # all the learners (scaled up from `tutorial_learners` of them)
    tutorial_learners: int  # learners the tutorial loop actually ran
    online_returns: tuple[float, ...] = ()


@dataclass(frozen=True)
class TasksResult:
    """Seconds of each side (medians), the tasks each split made, and why a side is
    missing (`cluster_note`)."""

    game: str
    seeds: int
    episodes: int
    tasks_s: float
    batch_s: float
    tasks: int
    local_s: float | None = None
    cluster_s: float | None = None
    cluster_tasks: int = 0
    cluster_note: str = ""


def measure_seeds(seeds: int, episodes: int, tutorial_share: float = 1.0) -> SeedsSpeed:
    """Time the comparison, then the tutorial loop on a share of its learners."""
    from tui_gym.session.experiments.compare import CompareSpec, run_compare

    spec = CompareSpec(GAME, ALGORITHMS, seeds, episodes, settings=SETTINGS)
    run_compare(CompareSpec(GAME, ALGORITHMS, 1, 1, settings=SETTINGS))  # compiled, once
    compare_s, result = timed(lambda: run_compare(spec), COMPARE_REPEATS)
    online = tuple(float(o.curve.mean.mean()) for o in result.outcomes)
    per_algorithm = max(1, min(seeds, math.ceil(seeds * tutorial_share)))
    (run,) = tutorial.measure([{"kind": "learners", "game": GAME, "algorithms": ALGORITHMS,
                                "hp": {**SETTINGS, "episodes": episodes},
                                "seeds": per_algorithm, "episodes": episodes}])
    return SeedsSpeed(
        game=GAME, algorithms=ALGORITHMS, seeds=seeds, episodes=episodes,
        compare_s=compare_s, tutorial_s=run["seconds"] * seeds / per_algorithm,
        tutorial_learners=per_algorithm * len(ALGORITHMS), online_returns=online,
    )


def measure_tasks(seeds: int, episodes: int, repeats: int = 3) -> TasksResult:
    """A comparison in tasks, recorded, against one batch; a sweep on a Dask LocalCluster
    against the local executor (where Dask is installed)."""
    from tui_gym.core.experiments import RunHistory, RunKind
    from tui_gym.session.experiments.compare import Arm, CompareSpec, Setup, execute, run_compare
    from tui_gym.session.experiments.sweep import SweepSpec, run_sweep

    spec = CompareSpec(GAME, ALGORITHMS, seeds, episodes, settings=SETTINGS)
    run_compare(CompareSpec(GAME, ALGORITHMS, 1, 1, settings=SETTINGS))  # compiled, once
    setup = Setup(GAME, seeds, episodes, {}, (), 0)
    arms = [Arm(name, SETTINGS, name) for name in ALGORITHMS]
    with tempfile.TemporaryDirectory(prefix="tui-gym-bench-") as tmp:
        with RunHistory(Path(tmp) / "runs.db") as history:
            tasks_s, result = timed(lambda: run_compare(spec, history=history), repeats)
        batch_s, _ = timed(lambda: execute(setup, arms, RunKind.COMPARE,
                                            task_seconds=math.inf), repeats)
    found = TasksResult(GAME, seeds, episodes, tasks_s, batch_s, int(result.tasks["total"]))
    sweep = SweepSpec(GAME, "q-learning", {"learning_rate": SWEEP_RATES}, seeds, episodes,
                      settings={k: v for k, v in SETTINGS.items() if k != "learning_rate"})
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        return replace(found, cluster_note="Dask is not installed (pip install 'tui-gym[dask]')")
    local_s, _ = timed(lambda: run_sweep(sweep, processes=CLUSTER_WORKERS), repeats)
    with LocalCluster(n_workers=CLUSTER_WORKERS, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=logging.ERROR) as cluster, \
            Client(cluster) as client:
        run_sweep(sweep, cluster=client)  # the workers import and compile, once
        cluster_s, swept = timed(lambda: run_sweep(sweep, cluster=client), repeats)
    return replace(found, local_s=local_s, cluster_s=cluster_s,
                   cluster_tasks=int(swept.tasks["total"]))
