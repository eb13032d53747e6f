"""`tui-gym runs prune`: the stored tasks of finished runs go (their curves and figures stay,
the file gives the space back); an unfinished run keeps its tasks and still resumes."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import RunHistory
from tui_gym.session.experiments.compare import CompareProgress, CompareSpec, run_compare

FINISHED = CompareSpec("frozenlake", ("q-learning", "sarsa"), seeds=3, episodes=3000)
STOPPED = CompareSpec("frozenlake", ("q-learning", "sarsa"), seeds=3, episodes=40, first_seed=9)


def test_prune_keeps_figures_and_what_an_unfinished_run_needs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = tmp_path / "runs.db"
    stop = threading.Event()

    def told(progress: CompareProgress) -> None:
        if progress.tasks_done >= 1:
            stop.set()

    with RunHistory(db) as history:
        run_compare(FINISHED, history=history, processes=0)
        stopped = run_compare(STOPPED, progress=told, stop=stop, history=history, processes=0)
        before = {r.id: (str(r.status), r.figures) for r in history.list_runs()}
        tasks = {i: len(history.read_tasks(i)) for i in before}
    assert stopped.interrupted and sorted(tasks.values()) == [0, 1, 1, 1]
    size = db.stat().st_size
    assert main(["runs", "prune", "--db", str(db), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {
        "schema": 1, "db": str(db), "runs": 2, "tasks": 2}
    assert db.stat().st_size < size
    with RunHistory(db) as history:
        assert {r.id: (str(r.status), r.figures) for r in history.list_runs()} == before
        assert {i: len(history.read_tasks(i)) for i in before} == {
            i: 0 if before[i][0] == "finished" else n for i, n in tasks.items()}
        resumed = run_compare(STOPPED, history=history, processes=0, resume=stopped.group)
    assert not resumed.interrupted
    assert main(["runs", "prune", "--db", str(db)]) == 0
    assert "removed 2 stored tasks of 2 finished runs" in capsys.readouterr().out
