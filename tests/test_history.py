"""The run history: recording runs, the queries `tui-gym runs` makes, CSV export."""

from __future__ import annotations

import csv
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from tui_gym.core.experiments import (
    STORED_POINTS,
    Curve,
    Figure,
    RunHistory,
    RunHistoryError,
    RunKind,
    RunRecorder,
    RunSpec,
    RunStatus,
    UnknownRunError,
    Versions,
    WrapperSetting,
    export_run_csv,
    list_runs,
    remove_run,
    show_run,
)

VERSIONS = Versions(tui_gym="0.1.0", gymnasium="1.4.0", numpy="2.0.0", python="3.11.0")


def spec(game: str = "blackjack", kind: str = "train", seed: int = 0, **extra: object) -> RunSpec:
    return RunSpec(
        kind=RunKind(kind),
        game=game,
        algorithm=str(extra.pop("algorithm", "q_learning")),
        game_params={"sab": False, "natural": False},
        hyperparameters={"learning_rate": 0.01, "discount": 0.95},
        seeds=(seed,),
        versions=VERSIONS,
        **extra,  # type: ignore[arg-type]
    )


@pytest.fixture
def db(tmp_path: Path) -> Path:
    return tmp_path / "data" / "tui-gym" / "runs.db"


def test_a_run_keeps_everything_it_was_given(db: Path) -> None:
    run_spec = RunSpec(
        kind=RunKind.TRAIN,
        game="gridworld",
        algorithm="sarsa",
        game_params={"size": 5},
        wrappers=(
            WrapperSetting("TimeLimit", {"max_episode_steps": 50}),
            WrapperSetting("FlattenObservation"),
        ),
        hyperparameters={"learning_rate": np.float64(0.5), "episodes": np.int64(300)},
        seeds=(1, 2, 3),
    )
    with RunHistory(db) as history:
        run_id = history.start_run(run_spec, started_at=1000.0)
        running = history.get_run(run_id)
        assert running.summary.status is RunStatus.RUNNING
        assert running.summary.ended_at is None and running.summary.seconds is None
        history.update(
            run_id,
            curves=[Curve.per_episode("return", np.linspace(-1, 0, 300))],
            figures=[Figure("mean_return_last", -0.02, "return", 0.01)],
            agent_path=db.parent / "agent.tgym",
            status=RunStatus.FINISHED,
            ended_at=1012.5,
        )
        record = history.get_run(run_id)
    summary = record.summary
    assert (summary.kind, summary.game, summary.algorithm) == ("train", "gridworld", "sarsa")
    assert summary.seeds == (1, 2, 3)
    assert summary.status is RunStatus.FINISHED
    assert (summary.started_at, summary.ended_at, summary.seconds) == (1000.0, 1012.5, 12.5)
    assert summary.figures == (Figure("mean_return_last", -0.02, "return", 0.01),)
    assert record.game_params == {"size": 5}
    assert [w.name for w in record.wrappers] == ["TimeLimit", "FlattenObservation"]
    assert record.wrappers[0].params == {"max_episode_steps": 50}
    assert record.hyperparameters == {"learning_rate": 0.5, "episodes": 300}
    assert record.versions == Versions.current()
    assert record.agent_path == str(db.parent / "agent.tgym")
    curve = record.curve("return")
    assert curve is not None and len(curve) == STORED_POINTS
    assert curve.episodes[-1] == 300
    data = record.to_json()
    assert data["status"] == "finished" and data["curves"][0]["name"] == "return"
    assert data["versions"]["python"] == Versions.current().python


def test_curves_are_bounded_whatever_the_run_length(db: Path) -> None:
    with RunHistory(db) as history:
        run_id = history.start_run(spec())
        long = np.random.default_rng(0).normal(size=200_000)
        history.update(run_id, curves=[Curve.per_episode("return", long)])
        history.update(run_id, curves=[Curve.per_episode("wide", long[:2000])], max_points=500)
        record = history.get_run(run_id)
        with pytest.raises(ValueError):
            history.update(run_id, curves=[Curve.per_episode("x", long)], max_points=501)
    stored = record.curve("return")
    assert stored is not None and len(stored) == STORED_POINTS
    assert stored.episodes[-1] == 200_000
    # Each stored point is the mean of its bucket of episodes (to float16 precision).
    edges = np.concatenate([[0], stored.episodes])
    expected = [long[lo:hi].mean() for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    assert stored.values == pytest.approx(expected, abs=2e-3)
    wide = record.curve("wide")
    assert wide is not None and len(wide) == 500


def test_curves_and_figures_are_added_or_replaced_by_name(db: Path) -> None:
    with RunHistory(db) as history:
        run_id = history.start_run(spec())
        history.update(run_id, curves=[Curve("a", [1, 2], [1.0, 2.0]), Curve("b", [1], [5.0])])
        history.update(run_id, curves=[Curve("a", [1, 2, 3], [0.5, 0.25, 0.125])])
        history.update(run_id, figures=[Figure("first", 1.0), Figure("second", 2.0, "s")])
        history.update(run_id, figures=[Figure("third", float("nan")), Figure("first", 10.0, "x")])
        record = history.get_run(run_id)
    assert {c.name: c.values.tolist() for c in record.curves} == {
        "a": [0.5, 0.25, 0.125],
        "b": [5.0],
    }
    figures = record.summary.figures
    assert [f.name for f in figures] == ["first", "second", "third"]  # a known name keeps its place
    assert (figures[0].value, figures[0].unit) == (10.0, "x")
    assert np.isnan(figures[2].value)
    assert record.summary.to_json()["figures"][2]["value"] is None
    assert record.agent_path is None


def test_listing_is_newest_first_and_filters(db: Path) -> None:
    with RunHistory(db) as history:
        ids = {}
        for at, (game, kind) in enumerate(
            [("blackjack", "train"), ("gridworld", "train"), ("blackjack", "compare")]
        ):
            ids[(game, kind)] = history.start_run(spec(game, kind), started_at=100.0 + at)
        newest_first = [r.id for r in history.list_runs()]
        assert newest_first == [
            ids[("blackjack", "compare")],
            ids[("gridworld", "train")],
            ids[("blackjack", "train")],
        ]
        assert [r.game for r in history.list_runs(game="Blackjack")] == ["blackjack"] * 2
        assert [r.kind for r in history.list_runs(kind="train")] == ["train", "train"]
        assert [r.id for r in history.list_runs(game="blackjack", kind=RunKind.TRAIN)] == [
            ids[("blackjack", "train")]
        ]
        assert len(history.list_runs(limit=1)) == 1
        with pytest.raises(ValueError):
            history.list_runs(kind="nonsense")


def test_recorder_finishes_the_run(db: Path) -> None:
    with RunHistory(db) as history:
        with RunRecorder(history, spec()) as recorder:
            recorder.extend("return", np.ones(1000))
            recorder.extend("return", [0.0] * 1000)
            recorder.put_curve(Curve("exact_gap", [1000, 2000], [0.5, 0.1]))
            recorder.add_figures(Figure("exact_gap", 0.1))
        history.update(recorder.run_id, agent_path="agent.tgym")
        record = history.get_run(recorder.run_id)
    assert record.summary.status is RunStatus.FINISHED
    assert record.summary.ended_at is not None
    assert record.agent_path == "agent.tgym"
    curve = record.curve("return")
    assert curve is not None and len(curve) <= STORED_POINTS and curve.episodes[-1] == 2000
    assert curve.values[0] == 1.0 and curve.values[-1] == 0.0
    gap = record.curve("exact_gap")
    assert gap is not None and gap.episodes.tolist() == [1000, 2000]


def test_ctrl_c_keeps_what_the_run_had(db: Path) -> None:
    with RunHistory(db) as history:
        with pytest.raises(KeyboardInterrupt), RunRecorder(history, spec()) as recorder:
            recorder.extend("return", np.arange(50.0))
            recorder.add_figures(Figure("episodes", 50, "episodes"))
            raise KeyboardInterrupt
        record = history.get_run(recorder.run_id)
        assert record.summary.status is RunStatus.INTERRUPTED
        assert record.summary.ended_at is not None
        curve = record.curve("return")
        assert curve is not None and curve.episodes[-1] == 50
        assert record.summary.figures[0].value == 50

        with pytest.raises(RuntimeError), RunRecorder(history, spec()) as failing:
            raise RuntimeError("boom")
        assert history.get_run(failing.run_id).summary.status is RunStatus.FAILED

        finished_early = RunRecorder(history, spec())
        finished_early.finish(RunStatus.INTERRUPTED)
        with finished_early:
            pass  # already finished: leaving does not change it
        assert history.get_run(finished_early.run_id).summary.status is RunStatus.INTERRUPTED


def test_unknown_run_ids_and_bad_updates(db: Path) -> None:
    with RunHistory(db) as history:
        run_id = history.start_run(spec())
        for action in (
            lambda: history.get_run(999),
            lambda: history.remove_run(999),
            lambda: history.update(999, status=RunStatus.FINISHED),
            lambda: history.update(999, figures=[Figure("x", 1.0)]),
            lambda: history.update(999, agent_path="x"),
        ):
            with pytest.raises(UnknownRunError, match=f"no run 999 in {db}"):
                action()
        with pytest.raises(ValueError):
            history.update(run_id, status=RunStatus.RUNNING)
        with pytest.raises(ValueError, match="hyperparameters cannot be recorded"):
            history.start_run(
                RunSpec(RunKind.TRAIN, "blackjack", "q", hyperparameters={"x": object()})
            )
        with pytest.raises(ValueError, match="game's parameters cannot be recorded"):
            history.start_run(
                RunSpec(RunKind.TRAIN, "blackjack", "q", game_params={"x": float("inf")})
            )
        assert [r.id for r in history.list_runs()] == [run_id]


def test_removing_a_run_removes_its_curves_and_unused_settings(db: Path) -> None:
    with RunHistory(db) as history:
        keep = history.start_run(spec(seed=1))
        gone = history.start_run(spec(seed=2, algorithm="sarsa"))
        history.update(gone, curves=[Curve("a", [1], [1.0])])
        removed = history.remove_run(gone)
        assert removed.id == gone and removed.algorithm == "sarsa"
        assert [r.id for r in history.list_runs()] == [keep]
        conn = history._conn
        assert conn.execute("SELECT COUNT(*) FROM curves").fetchone()[0] == 0
        assert conn.execute("SELECT COUNT(*) FROM settings").fetchone()[0] == 1
        # Ids are never reused.
        assert history.start_run(spec()) > gone


def test_runs_commands_without_a_history_create_nothing(tmp_path: Path) -> None:
    db = tmp_path / "none" / "runs.db"
    listing = list_runs(str(db))
    assert listing.runs == () and listing.db == db
    assert listing.to_json() == {"db": str(db), "runs": [], "damaged": [], "total": 0}
    with pytest.raises(UnknownRunError, match="no run 3"):
        show_run(3, str(db))
    with pytest.raises(UnknownRunError):
        remove_run(3, str(db))
    with pytest.raises(UnknownRunError):
        export_run_csv(3, tmp_path / "x.csv", str(db))
    assert not db.parent.exists() and not (tmp_path / "x.csv").exists()


def test_runs_commands(db: Path, tmp_path: Path) -> None:
    with RunHistory(db) as history:
        first = history.start_run(spec("blackjack"), started_at=1.0)
        second = history.start_run(spec("gridworld"), started_at=2.0)
    assert [r.id for r in list_runs(str(db)).runs] == [second, first]
    assert [r.id for r in list_runs(str(db), game="gridworld").runs] == [second]
    assert show_run(first, str(db)).summary.game == "blackjack"
    removed = remove_run(first, str(db))
    assert removed.run.id == first and removed.to_json()["removed"]["id"] == first
    with pytest.raises(UnknownRunError):
        show_run(first, str(db))


def test_csv_export_round_trip(db: Path, tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    with RunHistory(db) as history:
        run_id = history.start_run(spec())
        history.update(
            run_id,
            curves=[
                Curve.per_episode("return", rng.normal(size=1000)),
                Curve.per_episode("length", rng.uniform(1, 9, size=1000)),
                Curve("exact, gap", [250, 500, 1000], [0.3, np.nan, 0.01]),
            ],
        )
        stored = {c.name: c for c in history.get_run(run_id).curves}
    target = tmp_path / "out" / "curves.csv"
    target.parent.mkdir()
    target.write_text("old contents")
    export = export_run_csv(run_id, target, str(db))
    assert export.path == target and export.columns[0] == "episode"
    with target.open(newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    assert header == list(export.columns) == ["episode", *stored]
    assert len(body) == export.rows
    episodes = [int(row[0]) for row in body]
    assert episodes == sorted(set(episodes))
    for column, name in enumerate(header[1:], start=1):
        cells = {int(row[0]): row[column] for row in body if row[column] != ""}
        curve = stored[name]
        present = ~np.isnan(curve.values)
        assert list(cells) == curve.episodes[present].tolist()
        assert [float(v) for v in cells.values()] == curve.values[present].tolist()
    # Written through a temporary file: none is left, and the file has the usual permissions.
    assert sorted(p.name for p in target.parent.iterdir()) == ["curves.csv"]
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask
    with pytest.raises(RunHistoryError, match="missing does not exist"):
        export_run_csv(run_id, tmp_path / "missing" / "x.csv", str(db))


def test_new_file_and_folder_get_the_usual_permissions(db: Path) -> None:
    assert not db.parent.exists()
    RunHistory(db).close()
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(db.stat().st_mode) == 0o666 & ~umask
    assert stat.S_IMODE(db.parent.stat().st_mode) == 0o777 & ~umask
