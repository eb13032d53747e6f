"""`tui-gym runs` and the recording of `tui-gym train`, through the command line."""

from __future__ import annotations

import json
import multiprocessing
import sqlite3
from pathlib import Path

import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import RunHistory, RunSpec
from tui_gym.core.experiments.connection import APPLICATION_ID

SHORT = ["--episodes", "3000", "--eval-episodes", "200"]


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def runs_json(capsys: pytest.CaptureFixture[str], db: Path, *extra: str) -> list[dict]:
    code, out, err = run_cli(capsys, "runs", "--json", "--db", str(db), *extra)
    assert code == 0, err
    return json.loads(out)["runs"]


def test_train_is_recorded_with_settings_curves_and_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    agent = tmp_path / "bj.tgym"
    code, out, err = run_cli(capsys, "train", "blackjack", *SHORT, "--seed", "3",
                             "--learning-rate", "0.05", "--save", str(agent), "--json",
                             "--db", str(db))
    assert code == 0, err
    trained = json.loads(out)
    [run] = runs_json(capsys, db)
    assert run["id"] == trained["run"]
    assert (run["kind"], run["game"], run["algorithm"], run["seeds"], run["status"]) == (
        "train", "blackjack", "q-learning", [3], "finished")
    figures = {f["name"]: f for f in run["figures"]}
    assert {"mean_return_last", "exact_value", "exact_gap", "eval_mean_return"} <= set(figures)
    assert figures["exact_gap"]["value"] == pytest.approx(trained["eval"]["gap"])

    code, out, err = run_cli(capsys, "runs", "show", str(run["id"]), "--json", "--db", str(db))
    assert code == 0, err
    record = json.loads(out)
    assert record["hyperparameters"]["learning_rate"] == 0.05
    assert record["hyperparameters"]["episodes"] == 3000
    assert record["game_params"] == trained["env_kwargs"]
    assert record["agent_path"] == str(agent.resolve())
    assert record["versions"]["gymnasium"]
    curves = {c["name"]: c for c in record["curves"]}
    assert set(curves) == {"return", "exact_value"}
    returns = curves["return"]
    assert 2 <= len(returns["episodes"]) <= 100 and returns["episodes"][-1] <= 3000
    assert all(-1.5 <= v <= 1.5 for v in returns["values"])
    assert curves["exact_value"]["episodes"][0] == 0  # the untrained policy's value first
    # Curves are stored to about three significant digits; figures in full.
    final = figures["exact_value"]["value"]
    assert curves["exact_value"]["values"][-1] == pytest.approx(final, abs=1e-3)

    code, out, _ = run_cli(capsys, "runs", "show", str(run["id"]), "--db", str(db))
    assert code == 0 and "exact gap" in out and "q-learning" in out


def test_a_prediction_learners_train_run_records_the_rms_error_of_its_values(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    code, out, err = run_cli(capsys, "train", "random-walk", "--algorithm", "td0", "--episodes",
                             "200", "--eval-episodes", "20", "--json", "--db", str(db))
    assert code == 0, err
    trained = json.loads(out)
    [run] = runs_json(capsys, db)
    figures = {f["name"]: f["value"] for f in run["figures"]}
    # Its greedy policy is no figure of a prediction learner: the error of V is.
    assert "exact_value" not in figures and "exact_gap" not in figures
    assert figures["rms_error"] == pytest.approx(trained["rms_error"])
    code, out, err = run_cli(capsys, "runs", "show", str(run["id"]), "--json", "--db", str(db))
    curves = {c["name"]: c for c in json.loads(out)["curves"]}
    assert set(curves) == {"return", "rms_error"}
    assert curves["rms_error"]["episodes"][0] == 0 and curves["rms_error"]["values"][0] > 0


def test_list_filter_export_and_remove(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "160")
    db = tmp_path / "runs.db"
    for game in ("blackjack", "gridworld"):
        assert run_cli(capsys, "train", game, *SHORT, "--db", str(db))[0] == 0
    assert run_cli(capsys, "train", "blackjack", *SHORT, "--db", str(db), "--no-record")[0] == 0
    runs = runs_json(capsys, db)
    assert [r["game"] for r in runs] == ["gridworld", "blackjack"]  # newest first
    assert [r["game"] for r in runs_json(capsys, db, "--game", "GridWorld")] == ["gridworld"]
    code, out, _ = run_cli(capsys, "runs", "--db", str(db))
    assert code == 0 and "gridworld" in out and "blackjack" in out

    blackjack = runs[1]["id"]
    csv_path = tmp_path / "curves.csv"
    code, out, err = run_cli(capsys, "runs", "export", str(blackjack), "--csv", str(csv_path),
                             "--db", str(db))
    assert code == 0, err
    lines = csv_path.read_text().splitlines()
    assert lines[0] == "episode,exact_value,return" and len(lines) > 3

    code, out, err = run_cli(capsys, "runs", "rm", str(blackjack), "--db", str(db))
    assert code == 0 and f"removed run {blackjack}" in out
    assert [r["game"] for r in runs_json(capsys, db)] == ["gridworld"]
    code, out, err = run_cli(capsys, "runs", "show", str(blackjack), "--db", str(db))
    assert code == 2 and out == ""
    assert err == f"tui-gym: error: no run {blackjack} in {db}\n"
    with pytest.raises(SystemExit) as exit_:
        main(["runs", "rm", "0", "--db", str(db)])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "a run id" in err and err.count("\n") == 1


def test_db_may_come_before_the_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    assert run_cli(capsys, "--db", str(db), "train", "blackjack", *SHORT)[0] == 0
    code, out, _ = run_cli(capsys, "--db", str(db), "runs", "--json")
    assert code == 0 and len(json.loads(out)["runs"]) == 1
    code, out, _ = run_cli(capsys, "runs", "--db", str(db), "show", "1", "--json")
    assert code == 0 and json.loads(out)["id"] == 1


def test_the_env_variable_chooses_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "from-env.db"
    monkeypatch.setenv("TUI_GYM_DB", str(db))
    assert run_cli(capsys, "train", "blackjack", *SHORT)[0] == 0
    code, out, _ = run_cli(capsys, "runs", "--json")
    assert code == 0 and json.loads(out)["db"] == str(db)
    assert len(json.loads(out)["runs"]) == 1


def test_a_file_that_is_not_a_history_is_never_touched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "notes.db"
    db.write_bytes(b"my notes, not a database\n" * 50)
    before = db.read_bytes()
    code, out, err = run_cli(capsys, "runs", "--db", str(db))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "is not a tui-gym run history" in err
    # Training still trains; the run is not recorded, and the file stays as it was.
    code, out, err = run_cli(capsys, "train", "blackjack", *SHORT, "--json", "--db", str(db))
    assert code == 0 and json.loads(out)["run"] is None
    assert err.count("\n") == 1 and "not recorded" in err and "left untouched" in err
    assert db.read_bytes() == before


def test_a_history_from_a_newer_tui_gym_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    RunHistory(db).close()
    with sqlite3.connect(db) as conn:
        conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
        conn.execute("PRAGMA user_version = 99")
    for argv in (("runs",), ("runs", "show", "1"), ("train", "blackjack", *SHORT)):
        code, _, err = run_cli(capsys, *argv, "--db", str(db))
        assert err.count("\n") == 1 and "newer tui-gym" in err, argv
        assert code == (0 if argv[0] == "train" else 2)


def _train_three(db: str, first_seed: int) -> None:
    import contextlib
    import io

    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for seed in range(first_seed, first_seed + 3):
            code = main(["train", "blackjack", "--episodes", "300", "--eval-episodes", "5",
                         "--engine", "env", "--seed", str(seed), "--db", db])
            if code != 0:
                raise SystemExit(code)


def test_two_processes_recording_at_once_lose_nothing(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    # Forked, so each process starts with tui-gym already imported and both write at once.
    context = multiprocessing.get_context("fork")
    procs = [context.Process(target=_train_three, args=(str(db), first)) for first in (0, 100)]
    for proc in procs:
        proc.start()
    for proc in procs:
        proc.join(120)
        assert proc.exitcode == 0
    with RunHistory(db) as history:
        runs = history.list_runs()
        assert sorted(r.seeds[0] for r in runs) == [0, 1, 2, 100, 101, 102]
        assert all(r.status == "finished" for r in runs)
        assert all(history.get_run(r.id).curve("return") is not None for r in runs)


def record(db: Path, *runs: tuple[str, str, str, str]) -> None:
    """Runs (kind, game, algorithm, status) straight into the history."""
    from tui_gym.core.experiments import Figure, RunSpec, RunStatus

    with RunHistory(db) as history:
        for seed, (kind, game, algorithm, status) in enumerate(runs):
            run_id = history.start_run(RunSpec(kind, game, algorithm, seeds=(seed,)))
            history.update(run_id, figures=[Figure("mean_return_last", 0.5)],
                           status=None if status == "running" else RunStatus(status))


def test_the_listing_fits_80_columns_without_cutting_a_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "runs.db"
    record(db, ("train", "frozenlake", "expected-sarsa", "finished"),
           ("compare", "cliffwalking", "double-q", "interrupted"),
           ("sweep", "blackjack", "monte-carlo", "failed"))
    for width in (80, 50):
        monkeypatch.setenv("COLUMNS", str(width))
        code, out, err = run_cli(capsys, "runs", "--db", str(db))
        assert code == 0, err
        table = out.splitlines()[2:7]  # the header, its rule and the three runs
        if width == 80:
            assert all(len(line) <= width for line in table), table
            assert "seeds" not in table[0] and "took" not in table[0]  # dropped to fit
        # Narrower, the terminal wraps the lines: never is a name cut.
        for name in ("frozenlake", "expected-sarsa", "cliffwalking", "double-q", "monte-carlo",
                     "compare (interrupted)", "sweep (failed)", "return"):
            assert name in out, (width, name)
        assert "…" not in out
    monkeypatch.setenv("COLUMNS", "160")
    code, out, _ = run_cli(capsys, "runs", "--db", str(db))
    assert all(column in out.splitlines()[2] for column in ("seeds", "started", "took"))


def test_the_listing_is_a_screenful_unless_asked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "runs.db"
    record(db, *[("train", "blackjack", "q-learning", "finished")] * 40)
    monkeypatch.setenv("LINES", "24")
    monkeypatch.setenv("COLUMNS", "100")
    code, out, err = run_cli(capsys, "runs", "--db", str(db))
    assert code == 0, err
    assert len(out.splitlines()) <= 24 and "the newest 15 of 40 runs" in out
    assert out.count(" blackjack ") == 15
    code, out, _ = run_cli(capsys, "runs", "--db", str(db), "--limit", "0")
    assert out.count(" blackjack ") == 40 and "newest" not in out
    code, out, _ = run_cli(capsys, "runs", "--db", str(db), "--limit", "3")
    assert out.count(" blackjack ") == 3 and "the newest 3 of 40 runs" in out
    listing = json.loads(run_cli(capsys, "runs", "--db", str(db), "--json")[1])
    assert len(listing["runs"]) == 40 and listing["total"] == 40
    listing = json.loads(run_cli(capsys, "runs", "--db", str(db), "--json", "--limit", "5")[1])
    assert [r["id"] for r in listing["runs"]] == [40, 39, 38, 37, 36] and listing["total"] == 40


def test_a_damaged_history_says_how_to_recover_and_recover_copies_what_reads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import numpy as np

    monkeypatch.setenv("COLUMNS", "400")  # the paths on one line each
    from tui_gym.core.experiments import Curve

    db = tmp_path / "runs.db"
    with RunHistory(db) as history:
        for seed in range(60):
            run_id = history.start_run(RunSpec("train", "blackjack", "q-learning", seeds=(seed,)))
            history.update(run_id, curves=[Curve.per_episode("return", np.zeros(300))])
    conn = sqlite3.connect(db)
    root = conn.execute("SELECT rootpage FROM sqlite_master WHERE name = 'curves'").fetchone()[0]
    page_size = conn.execute("PRAGMA page_size").fetchone()[0]
    conn.close()
    data = bytearray(db.read_bytes())
    data[(root - 1) * page_size: root * page_size] = b"\xff" * page_size  # the curves' table
    db.write_bytes(bytes(data))
    damaged = db.read_bytes()
    assert len(json.loads(run_cli(capsys, "runs", "--db", str(db), "--json")[1])["runs"]) == 60
    code, out, err = run_cli(capsys, "runs", "show", "7", "--db", str(db))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "is damaged" in err and f"tui-gym runs --recover --db {db}" in err

    code, out, err = run_cli(capsys, "runs", "--recover", "--db", str(db))
    assert code == 0, err
    copy = tmp_path / "runs.recovered.db"
    said = " ".join(out.split())
    assert f"copied 60 runs from {db} into {copy}; 60 of them without their curves" in said
    assert f"tui-gym runs --db {copy}" in said and "SQLite finds:" in said
    assert db.read_bytes() == damaged  # the original is never written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs.db", "runs.recovered.db"]
    listing = json.loads(run_cli(capsys, "runs", "--db", str(copy), "--json")[1])
    assert sorted(r["seeds"][0] for r in listing["runs"]) == list(range(60))
    conn = sqlite3.connect(copy)
    assert conn.execute("PRAGMA integrity_check").fetchall() == [("ok",)]
    conn.close()
    # Again: a second copy beside the first, which stays as it was.
    first = copy.read_bytes()
    code, out, _ = run_cli(capsys, "runs", "--recover", "--db", str(db), "--json")
    assert code == 0 and json.loads(out)["target"] == str(tmp_path / "runs.recovered-2.db")
    assert copy.read_bytes() == first


def test_recover_says_so_when_nothing_can_be_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "runs.db"
    db.write_bytes(b"not a database at all\n" * 100)
    code, out, err = run_cli(capsys, "runs", "--recover", "--db", str(db))
    assert code == 2 and out == "" and err.count("\n") == 1 and "nothing can be read" in err
    assert [p.name for p in tmp_path.iterdir()] == ["runs.db"]
    code, _, err = run_cli(capsys, "runs", "--recover", "show", "1", "--db", str(db))
    assert code == 2 and "--recover" in err
