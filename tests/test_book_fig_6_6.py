"""Figure 6.6: Sarsa, Expected Sarsa and Q-learning on CliffWalking against α, its claims at a
few runs, the book's task list under --full, and a recorded figure resumed."""

from __future__ import annotations

from functools import partial
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from tui_gym.core.experiments.history import RunHistory
from tui_gym.session.book import figure_named, runs, td
from tui_gym.session.book.figure import FigureOptions, FigureTasks
from tui_gym.session.experiments import compare
from tui_gym.session.experiments.compare import ResumeError


@pytest.fixture(autouse=True)
def _on_this_thread(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every figure plays on the test's thread (`processes=0`), with no estimate of whether
    to spread it over child processes: a seed's run is the same wherever it runs
    (tests/test_compare.py::test_seeds_in_child_processes_match_the_calling_thread)."""
    monkeypatch.setattr(runs, "execute", partial(runs.execute, processes=0))


def test_the_books_claims_at_a_few_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(td, "ASYMPTOTIC_RUNS", 6)
    result = figure_named("6.6").run(FigureOptions(runs=100, episodes=1500, seed=100),
                                     lambda *_: None)
    assert result.runs == 100 and len(result.checks) == 6
    assert result.ok, [c for c in result.checks if not c.ok]
    assert [s.label for s in result.series] == ["Sarsa", "Expected Sarsa", "Q-learning"] * 2
    assert all(len(s.x) == 10 for s in result.series[:3])  # every interim point is on the chart


def test_full_hands_the_executor_the_books_tasks(monkeypatch: pytest.MonkeyPatch) -> None:
    asked: list[tuple[Any, list[Any]]] = []

    def execute(setup: Any, arms: list[Any], kind: Any, **_: Any) -> Any:
        asked.append((setup, arms))
        values = np.broadcast_to(np.zeros(1), (len(arms), setup.seeds, setup.episodes))
        return SimpleNamespace(values=values, exact=None, interrupted=False, group=None,
                               prepared=SimpleNamespace(optimum=None), tasks={})

    monkeypatch.setattr(runs, "execute", execute)
    td.fig_6_6.run(FigureOptions(full=True), lambda *_: None)
    assert [(s.game, s.seeds, s.episodes) for s, _ in asked] == [
        ("cliffwalking", 50_000, 100), ("cliffwalking", 10, 100_000)]
    for _, arms in asked:
        assert [(a.algorithm, a.settings["learning_rate"]) for a in arms] == [
            (name, alpha) for name in ("sarsa", "expected-sarsa", "q-learning")
            for alpha in (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)]
        assert all(a.settings["epsilon_start"] == a.settings["epsilon_final"] == 0.1
                   for a in arms)
    # The interim as tasks of 500 seeds: 100 a learner, every run in exactly one.
    setup, arms = asked[0]
    prepared = compare.prepare(setup, arms[:1])
    jobs = compare._jobs(setup, arms[:1], prepared, [list(range(setup.seeds))], pieces=100)
    assert len(jobs) == 100 and {len(j.seeds) for j in jobs} == {500}
    assert sorted(s for j in jobs for s in j.seeds) == list(range(50_000))


def _small(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(td, "ASYMPTOTIC_RUNS", 2)


def test_a_recorded_figure_resumes_with_only_the_missing_tasks(
        tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    _small(monkeypatch)
    options = {"runs": 3, "episodes": 40, "seed": 7}
    with RunHistory(tmp_path / "runs.db") as history:
        first = FigureTasks(history)
        whole = td.fig_6_6.run(FigureOptions(**options, tasks=first), lambda *_: None)
        ids = history.group_ids(first.group)
        assert first.group == ids[0] and len(ids) == 60 and first.landed == first.tasks
        for run_id in ids[30:]:  # as if stopped before the asymptotic runs began
            history.remove_run(run_id)
        again = FigureTasks(history, resume=first.group)
        resumed = td.fig_6_6.run(FigureOptions(**options, tasks=again), lambda *_: None)
        now = history.group_ids(first.group)
        assert now[:30] == ids[:30] and len(now) == 60 and min(now[30:]) > max(ids)
    for a, b in zip(whole.series, resumed.series, strict=True):
        assert a.label == b.label and a.y.tolist() == b.y.tolist()
    assert [c.measured for c in whole.checks] == [c.measured for c in resumed.checks]


def test_resuming_with_other_settings_or_from_a_later_run_is_refused(
        tmp_path: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    _small(monkeypatch)
    with RunHistory(tmp_path / "runs.db") as history:
        first = FigureTasks(history)
        td.fig_6_6.run(FigureOptions(runs=2, episodes=20, tasks=first), lambda *_: None)
        assert first.group is not None
        with pytest.raises(ResumeError, match="other settings"):
            td.fig_6_6.run(FigureOptions(runs=3, episodes=20, tasks=FigureTasks(
                history, resume=first.group)), lambda *_: None)
        with pytest.raises(ResumeError, match=f"resume run {first.group}$"):
            td.fig_6_6.run(FigureOptions(runs=2, episodes=20, tasks=FigureTasks(
                history, resume=first.group + 1)), lambda *_: None)


def test_the_command_records_full_runs_and_resumes_them(
        tmp_path: Any, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    from tui_gym.cli import main

    monkeypatch.setattr(td, "FULL_ASYMPTOTIC_RUNS", 2)
    db = str(tmp_path / "runs.db")
    small = ["book", "6.6", "--full", "--runs", "2", "--episodes", "20", "--db", db]
    main(small)
    out = capsys.readouterr().out
    assert "tasks in" in out and "kept in the run history as runs 1…" in out
    main([*small, "--resume", "1"])
    assert "kept in the run history as runs 1…" in capsys.readouterr().out
    assert main([*small[:4], "3", *small[5:], "--resume", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("tui-gym: error: run 1 was recorded with other")
    with RunHistory(tmp_path / "runs.db") as history:
        assert len(history.group_ids(1)) == 60


def test_ctrl_c_keeps_the_finished_tasks_and_says_how_to_resume(
        tmp_path: Any, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    import signal

    from tui_gym.cli import main

    monkeypatch.setattr(td, "FULL_ASYMPTOTIC_RUNS", 2)
    calls: list[int] = []
    execute = runs.execute

    def interrupted_second(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        if len(calls) == 2:  # the interim part is kept; Ctrl+C as the asymptotic one starts
            signal.raise_signal(signal.SIGINT)
        return execute(*args, **kwargs)

    monkeypatch.setattr(runs, "execute", interrupted_second)
    db = str(tmp_path / "runs.db")
    small = ["book", "6.6", "--full", "--runs", "2", "--episodes", "20", "--db", db]
    assert main(small) == 130
    err = capsys.readouterr().err
    assert "kept 30 of 60 tasks as runs 1…; the same command with --resume 1" in err, err
    monkeypatch.setattr(runs, "execute", execute)
    main([*small, "--resume", "1"])
    assert "kept in the run history as runs 1…" in capsys.readouterr().out
