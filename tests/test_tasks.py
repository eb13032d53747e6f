"""Comparisons and sweeps as tasks: each finished task kept in the run history with its
inputs, figures aggregated from what is stored, interrupted runs resumed (also after a
SIGKILL), the same numbers on a Dask cluster, random search, and writers that lose nothing."""

from __future__ import annotations

import multiprocessing
import os
import signal
import sqlite3
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tui_gym.core.experiments import RunHistory, RunKind, RunSpec
from tui_gym.core.experiments.connection import MIGRATIONS
from tui_gym.core.experiments.records import TaskRecord
from tui_gym.session.experiments import compare
from tui_gym.session.experiments.compare import (
    CompareProgress,
    CompareSpec,
    ResumeError,
    run_compare,
)
from tui_gym.session.experiments.sweep import Range, SweepSpec, run_sweep

SPEC = CompareSpec("frozenlake", ["q-learning", "sarsa"], seeds=3, episodes=150)
SWEEP = SweepSpec("frozenlake", "q-learning", {"learning_rate": [0.05, 0.1, 0.2, 0.4]},
                  seeds=2, episodes=150)


def figures(result: Any) -> list[tuple[Any, ...]]:
    outcomes = [p.outcome for p in result.points] if hasattr(result, "points") else \
        result.outcomes
    return [(o.mean_return_last.mean, o.mean_return_last.ci95, o.exact_value,
             o.curve.mean.tolist()) for o in outcomes]


def stored(db: Path, group: int) -> list[tuple[Any, ...]]:
    with RunHistory(db) as history:
        return [(tuple(r.summary.figures), str(r.summary.status))
                for r in (history.get_run(i) for i in history.group_ids(group))]


def stop_after(tasks: int) -> tuple[threading.Event, Any]:
    stop = threading.Event()

    def progress(p: CompareProgress) -> None:
        if p.tasks_done >= tasks:
            stop.set()

    return stop, progress


def test_each_finished_task_is_kept_with_its_inputs(tmp_path: Path) -> None:
    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(SPEC, history=history, processes=0)
        assert result.tasks == {"done": 2, "total": 2}
        for outcome in result.outcomes:
            assert outcome.run_id is not None
            (task,) = history.read_tasks(outcome.run_id)
            assert task.seeds == (0, 1, 2) and task.rows == (0, 1, 2) and task.episodes == 150
            assert task.algorithm == outcome.algorithm
            assert task.hyperparameters == dict(outcome.hyperparameters)
            assert task.exact is not None and np.isfinite(task.returns).all()
            # The run's figures are the stored task's.
            assert outcome.curve.mean.tolist() == task.returns.mean(axis=0).tolist()


def test_an_older_history_gains_the_tasks_table(tmp_path: Path) -> None:
    db = tmp_path / "old.db"
    with RunHistory(db, migrations=MIGRATIONS[:2]) as old:
        run_id = old.start_run(RunSpec(kind=RunKind.COMPARE, game="frozenlake",
                                       algorithm="q-learning", seeds=(0,)))
    with RunHistory(db) as history:
        assert history.schema_version == 3
        task = TaskRecord((0,), (0,), 2, np.array([[1.0, 0.5]]))
        assert history.put_task(run_id, task)
        assert not history.put_task(run_id, task)  # a task that lands twice is kept once
        assert history.read_tasks(run_id)[0].returns.tolist() == [[1.0, 0.5]]
    version = sqlite3.connect(db).execute("PRAGMA user_version").fetchone()[0]
    assert version == 3


def test_a_stopped_run_resumes_to_the_uninterrupted_figures(tmp_path: Path) -> None:
    whole = run_compare(SPEC, processes=0)
    with RunHistory(tmp_path / "runs.db") as history:
        stop, progress = stop_after(1)
        first = run_compare(SPEC, history=history, processes=0, stop=stop, progress=progress)
        assert first.interrupted and first.group is not None
        assert sum(len(history.read_tasks(o.run_id)) for o in first.outcomes) == 1
        resumed = run_compare(SPEC, history=history, processes=0, resume=first.group)
    assert not resumed.interrupted and resumed.tasks == {"done": 2, "total": 2}
    assert [o.run_id for o in resumed.outcomes] == [first.group, first.group + 1]
    assert figures(resumed) == figures(whole)


def test_resume_with_other_settings_is_refused(tmp_path: Path) -> None:
    with RunHistory(tmp_path / "runs.db") as history:
        stop, progress = stop_after(1)
        first = run_compare(SPEC, history=history, processes=0, stop=stop, progress=progress)
        assert first.group is not None
        other = CompareSpec("frozenlake", ["q-learning", "sarsa"], seeds=3, episodes=150,
                            settings={"learning_rate": 0.3})
        with pytest.raises(ResumeError, match=r"learning_rate .* there, 0\.3 here"):
            run_compare(other, history=history, processes=0, resume=first.group)
        with pytest.raises(ResumeError, match="not this compare of 1"):
            run_compare(CompareSpec("frozenlake", ["sarsa"], seeds=3, episodes=150),
                        history=history, processes=0, resume=first.group)
        with pytest.raises(ResumeError, match="no run 99"):
            run_compare(SPEC, history=history, processes=0, resume=99)
        # Nothing ran: the stopped run keeps its one task.
        assert sum(len(history.read_tasks(o.run_id)) for o in first.outcomes) == 1


def test_the_cli_refuses_a_resume_in_one_line(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    from tui_gym.cli.main import main

    db = str(tmp_path / "runs.db")
    common = ["--seeds", "2", "--episodes", "50", "--processes", "0", "--db", db]
    assert main(["sweep", "frozenlake", "--algorithm", "sarsa", "--grid",
                 "learning_rate=0.1,0.2", *common, "--json"]) == 0
    capsys.readouterr()
    code = main(["sweep", "frozenlake", "--algorithm", "sarsa", "--grid",
                 "learning_rate=0.1,0.3", *common, "--resume", "1"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "other settings" in err


KILLED = """
import os, signal, sys
from tui_gym.core.experiments import RunHistory
from tui_gym.session.experiments.sweep import SweepSpec, run_sweep

spec = SweepSpec("frozenlake", "q-learning", {"learning_rate": [0.05, 0.1, 0.2, 0.4]},
                 seeds=2, episodes=150)

def progress(p):
    if p.tasks_done >= 2:
        os.kill(os.getpid(), signal.SIGKILL)

run_sweep(spec, history=RunHistory(sys.argv[1]), processes=0, progress=progress)
"""


def test_a_sweep_killed_with_sigkill_resumes_to_the_uninterrupted_figures(
        tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    killed = subprocess.run([sys.executable, "-c", KILLED, str(db)], timeout=120,
                            capture_output=True, text=True)
    assert killed.returncode == -signal.SIGKILL, killed.stderr
    with RunHistory(db) as history:
        kept = [len(history.read_tasks(i)) for i in history.group_ids(1)]
        assert sorted(kept) == [0, 0, 1, 1]
        resumed = run_sweep(SWEEP, history=history, processes=0, resume=1)
    with RunHistory(tmp_path / "whole.db") as history:
        whole = run_sweep(SWEEP, history=history, processes=0)
    assert figures(resumed) == figures(whole)
    assert [f for f, _ in stored(db, 1)] == [f for f, _ in stored(tmp_path / "whole.db", 1)]
    assert {s for _, s in stored(db, 1)} == {"finished"}


def test_a_local_cluster_gives_the_local_numbers(monkeypatch: pytest.MonkeyPatch) -> None:
    distributed = pytest.importorskip("distributed")
    # Workers report as often as they can: every update a task makes comes back.
    monkeypatch.setattr(compare, "PROGRESS_INTERVAL", 0.0)
    spec = CompareSpec("frozenlake", ["q-learning"], seeds=4, episodes=150)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        on_cluster = run_compare(spec, cluster=client)
    assert on_cluster.tasks["done"] == on_cluster.tasks["total"] >= 2
    assert figures(on_cluster) == figures(run_compare(spec, processes=0))


def test_a_missing_dask_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    from tui_gym.session.experiments.cluster import DASK_HINT, ClusterError

    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ClusterError, match=DASK_HINT.replace("[", r"\[").replace("]", r"\]")):
        run_compare(CompareSpec("frozenlake", ["q-learning"], 2, 20), cluster="local:2")


def test_random_search_draws_seeded_points_and_ranks_them() -> None:
    ranges = {"learning_rate": Range.parse("0.01:1:log"), "discount": Range.parse("0.9:1")}
    spec = SweepSpec("frozenlake", "q-learning", {}, seeds=2, episodes=100, ranges=ranges,
                     samples=4, sample_seed=3)
    points = spec.points()
    assert points == spec.points() and len(points) == 4
    assert points != SweepSpec("frozenlake", "q-learning", {}, seeds=2, episodes=100,
                               ranges=ranges, samples=4, sample_seed=4).points()
    assert all(0.01 <= p["learning_rate"] <= 1 and 0.9 <= p["discount"] <= 1 for p in points)
    result = run_sweep(spec, processes=0)
    ranked = result.ranked()
    assert [p.rank for p in ranked] == [1, 2, 3, 4]
    values = [p.figure for p in ranked]
    assert values == sorted(values, reverse=True)  # type: ignore[type-var]
    with pytest.raises(ValueError, match="above 0 for log"):
        Range.parse("0:1:log")
    with pytest.raises(ValueError, match="not both"):
        SweepSpec("frozenlake", "q-learning", {"discount": [0.9]}, seeds=1, episodes=10,
                  ranges=ranges, samples=2)


def _write_tasks(db: str, run_id: int, writer: int, count: int) -> None:
    with RunHistory(db) as history:
        for i in range(count):
            row = writer * count + i
            history.put_task(run_id, TaskRecord((row,), (row,), 3, np.full((1, 3), row)))


def test_four_concurrent_writers_lose_nothing(tmp_path: Path) -> None:
    db = str(tmp_path / "runs.db")
    with RunHistory(db) as history:
        run_id = history.start_run(RunSpec(kind=RunKind.SWEEP, game="frozenlake",
                                           algorithm="q-learning", seeds=tuple(range(80))))
    ctx = multiprocessing.get_context("fork")
    writers = [ctx.Process(target=_write_tasks, args=(db, run_id, w, 20)) for w in range(4)]
    for process in writers:
        process.start()
    for process in writers:
        process.join(timeout=120)
    assert [p.exitcode for p in writers] == [0, 0, 0, 0]
    with RunHistory(db) as history:
        tasks = history.read_tasks(run_id)
    assert sorted(t.rows[0] for t in tasks) == list(range(80))
    assert all(t.returns.tolist() == [[t.rows[0]] * 3] for t in tasks)
    assert os.path.getsize(db) > 0


def note_tasks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder where each task played leaves a file named by its process and its number."""
    ran = tmp_path / "ran"
    ran.mkdir()
    run_job = compare._run_job

    def noted(job: Any, stop: Any, report: Any) -> Any:
        (ran / f"{os.getpid()}.{job.index}").touch()
        return run_job(job, stop, report)

    monkeypatch.setattr(compare, "_run_job", noted)
    return ran


def test_tasks_in_child_processes_are_each_kept_once(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    # Spread however short the work, in tasks of one or two seeds.
    monkeypatch.setattr(compare, "SPREAD_SECONDS", 0.0)
    ran = note_tasks(tmp_path, monkeypatch)
    spec = CompareSpec("frozenlake", ["q-learning", "sarsa"], seeds=4, episodes=150)
    setup = compare.Setup("frozenlake", 4, 150, {}, (), 0)
    arms = [compare.Arm(name, {}, name) for name in spec.algorithms]
    with RunHistory(tmp_path / "runs.db") as history:
        done = compare.execute(setup, arms, RunKind.COMPARE, history=history, processes=2,
                               task_seconds=1e-9)
        tasks = [history.read_tasks(run_id) for run_id in history.group_ids(done.group or 0)]
    assert done.tasks == {"done": 8, "total": 8}
    # Played in two long-lived processes, task after task (not a process forked per task).
    played = [name.split(".") for name in os.listdir(ran)]
    assert len(played) == 8 and len({pid for pid, _ in played} - {str(os.getpid())}) <= 2
    assert [sorted(r for t in ts for r in t.rows) for ts in tasks] == [[0, 1, 2, 3]] * 2
    assert figures(done) == figures(run_compare(spec, processes=0))


def test_a_task_process_hands_over_after_its_share_of_seeds(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compare, "SPREAD_SECONDS", 0.0)
    monkeypatch.setattr(compare, "WORKER_SEEDS", 1)  # each process: one task, then another
    ran = note_tasks(tmp_path, monkeypatch)
    setup = compare.Setup("frozenlake", 4, 150, {}, (), 0)
    arms = [compare.Arm(name, {}, name) for name in SPEC.algorithms]
    done = compare.execute(setup, arms, RunKind.COMPARE, processes=2, task_seconds=1e-9)
    played = [name.split(".") for name in os.listdir(ran)]
    assert done.tasks == {"done": 8, "total": 8} and not done.interrupted
    assert len(played) == 8 and len({pid for pid, _ in played}) == 8
    spec = CompareSpec("frozenlake", list(SPEC.algorithms), seeds=4, episodes=150)
    assert figures(done) == figures(run_compare(spec, processes=0))


def test_a_task_process_killed_mid_run_ends_the_run_in_one_line(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compare, "SPREAD_SECONDS", 0.0)
    parent = os.getpid()
    run_job = compare._run_job

    def dies(job: Any, stop: Any, report: Any) -> Any:
        if os.getpid() != parent and job.index == 2:
            os.kill(os.getpid(), signal.SIGKILL)
        return run_job(job, stop, report)

    monkeypatch.setattr(compare, "_run_job", dies)
    setup = compare.Setup("frozenlake", 6, 150, {}, (), 0)
    arms = [compare.Arm("q-learning", {}, "q-learning")]
    with pytest.raises(compare.CompareError, match="^a training process ended with code -9$"):
        compare.execute(setup, arms, RunKind.COMPARE, processes=2, task_seconds=1e-9)


def test_a_run_stopped_before_some_tasks_began_shows_the_seeds_that_finished() -> None:
    setup = compare.Setup("frozenlake", 4, 100, {}, (), 0)
    arms = [compare.Arm("q-learning", {}, "q-learning")]
    prepared = compare.prepare(setup, arms)
    tally = compare._Tally(setup, arms, prepared)
    jobs = tally.add(compare._jobs(setup, arms, prepared, [[0, 1, 2, 3]], pieces=4))
    landed: list[Any] = []
    complete = compare._run_here(jobs, tally, lambda: len(landed) >= 2, lambda: None,
                                 landed.append)
    (outcome,) = tally.outcomes()
    assert not complete and len(landed) == 2 and outcome is not None
    assert outcome.seeds_done == 2 and outcome.episodes == 100
    assert outcome.curve.mean.tolist() == tally.returns[0, :2].mean(axis=0).tolist()


def test_the_cluster_comes_from_the_environment_too(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    from tui_gym.cli.main import main

    monkeypatch.setenv("TUI_GYM_CLUSTER", "local:0")
    code = main(["compare", "frozenlake", "--algorithms", "q-learning", "--seeds", "1",
                 "--episodes", "10", "--no-record"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.endswith("--cluster local:0: expected local:N with N from 1 to 256")


def test_a_worker_lost_mid_sweep_costs_a_retry_not_a_result(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        lost: list[str] = []

        def progress(p: CompareProgress) -> None:
            if p.tasks_done >= 1 and not lost:  # the first landed: a worker goes
                name, worker = next(iter(cluster.workers.items()))
                lost.append(str(name))
                client.sync(worker.close)

        with RunHistory(tmp_path / "runs.db") as history:
            swept = run_sweep(SWEEP, history=history, cluster=client, progress=progress)
            tasks = [history.read_tasks(i) for i in history.group_ids(swept.group or 0)]
    assert lost and swept.tasks["done"] == swept.tasks["total"] >= 4
    assert [sorted(r for t in ts for r in t.rows) for ts in tasks] == [[0, 1]] * 4
    assert figures(swept) == figures(run_sweep(SWEEP, processes=0))


def test_recovering_a_history_keeps_the_tasks_so_its_runs_still_resume(tmp_path: Path) -> None:
    from tui_gym.core.experiments.recover import recover

    db = tmp_path / "runs.db"
    with RunHistory(db) as history:
        stop, progress = stop_after(1)
        first = run_compare(SPEC, history=history, processes=0, stop=stop, progress=progress)
    recovery = recover(db)
    assert recovery.target is not None and recovery.copied == 2
    with RunHistory(recovery.target) as history:
        assert [len(history.read_tasks(i)) for i in (1, 2)] == [1, 0]
        resumed = run_compare(SPEC, history=history, processes=0, resume=first.group)
    assert figures(resumed) == figures(run_compare(SPEC, processes=0))


def test_the_estimate_that_sizes_tasks_counts_the_exact_valuations(
        monkeypatch: pytest.MonkeyPatch) -> None:
    setup = compare.Setup("frozenlake", 3, 10, {}, (), 0)
    arms = [compare.Arm("q-learning", {}, "q-learning")]
    prepared = compare.prepare(setup, arms)
    clock = [0.0]

    def valued(mdp: Any, tables: np.ndarray) -> np.ndarray:
        clock[0] += 1.0  # each valuation takes a second of this clock; training none
        return np.zeros(len(tables))

    monkeypatch.setattr(compare.time, "perf_counter", lambda: clock[0])
    monkeypatch.setattr(compare, "greedy_values", valued)
    checkpoints = len(compare.checkpoint_episodes(10))
    assert compare._estimate(prepared, arms, setup, None) == pytest.approx(3 * checkpoints)


def test_the_estimate_leaves_out_a_learners_first_call(monkeypatch: pytest.MonkeyPatch) -> None:
    # The first call of a learner's loop loads its compiled code: a second of this clock,
    # which would size the tasks as if every seed took that long.
    setup = compare.Setup("frozenlake", 100, 10, {}, (), 0)
    arms = [compare.Arm("q-learning", {}, "q-learning")]
    prepared = compare.prepare(setup, arms)
    clock, called = [0.0], []

    def play(learner: Any, arrays: Any, episodes: int, *_: Any, **__: Any) -> Any:
        clock[0] += 0.001 * episodes + (0.0 if called else 1.0)
        called.append(episodes)
        return np.zeros(episodes), []

    monkeypatch.setattr(compare.time, "perf_counter", lambda: clock[0])
    monkeypatch.setattr(compare, "play_learner", play)
    monkeypatch.setattr(compare, "greedy_values", lambda mdp, tables: np.zeros(len(tables)))
    assert compare._estimate(prepared, arms, setup, None) == pytest.approx(100 * 10 * 0.001)


def test_a_cluster_out_of_reach_records_no_run(tmp_path: Path) -> None:
    from tui_gym.session.experiments.cluster import ClusterError

    with RunHistory(tmp_path / "runs.db") as history:
        with pytest.raises(ClusterError, match="local:N with N from 1 to 256"):
            run_compare(CompareSpec("frozenlake", ["q-learning"], 2, 20), history=history,
                        cluster="local:0")
        assert history.count_runs() == 0
