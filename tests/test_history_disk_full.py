"""A history that fails while a command runs (a full disk) loses no result: `compare`, `sweep`
and `benchmark` print what they found, then say in one line that it was not recorded."""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import RunHistory
from tui_gym.core.experiments.connection import Connection

FULL = "database or disk is full"


@pytest.fixture
def db(tmp_path: Path) -> Path:
    path = tmp_path / "runs.db"
    RunHistory(path).close()  # made while there was room
    return path


@pytest.fixture
def full_after(monkeypatch: pytest.MonkeyPatch) -> Callable[[int], None]:
    """From the write after the first `n`, every write fails as SQLite's do on a full disk."""

    def arm(n: int) -> None:
        real = Connection._once
        writes = [0]

        def once(self: Connection, action: Callable[..., object], begin: str | None) -> object:
            if begin == "BEGIN IMMEDIATE":
                writes[0] += 1
                if writes[0] > n:
                    raise sqlite3.OperationalError(FULL)
            return real(self, action, begin)

        monkeypatch.setattr(Connection, "_once", once)

    return arm


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def not_recorded(err: str) -> None:
    assert err.count("\n") == 1 and err.startswith("tui-gym: ")
    assert "not recorded in the run history" in err and FULL in err


COMPARE = ("compare", "blackjack", "--algorithms", "q-learning,sarsa", "--seeds", "2",
           "--episodes", "50", "--processes", "0")
SWEEP = ("sweep", "blackjack", "--algorithm", "q-learning", "--grid",
         "learning_rate=0.1,0.5", "--seeds", "2", "--episodes", "50", "--processes", "0")


@pytest.mark.parametrize("writes_that_fit", [0, 2])  # the runs cannot start / cannot finish
def test_compare_prints_its_results_then_says_they_were_not_recorded(
    db: Path, full_after: Callable[[int], None], capsys: pytest.CaptureFixture[str],
    writes_that_fit: int,
) -> None:
    full_after(writes_that_fit)
    code, out, err = run_cli(capsys, *COMPARE, "--db", str(db), "--json")
    assert code == 0
    assert [r["algorithm"] for r in json.loads(out)["results"]] == ["q-learning", "sarsa"]
    not_recorded(err)
    code, out, err = run_cli(capsys, *COMPARE, "--db", str(db))
    assert code == 0 and "q-learning" in out and "sarsa" in out and "95% band" in out
    assert "recorded in the run history as" not in out
    not_recorded(err)


def test_sweep_prints_its_results_then_says_they_were_not_recorded(
    db: Path, full_after: Callable[[int], None], capsys: pytest.CaptureFixture[str]
) -> None:
    full_after(2)
    code, out, err = run_cli(capsys, *SWEEP, "--db", str(db), "--json")
    assert code == 0 and len(json.loads(out)["points"]) == 2
    not_recorded(err)
    code, out, err = run_cli(capsys, *SWEEP, "--db", str(db))
    assert code == 0 and "learning_rate" in out
    not_recorded(err)


def test_benchmark_prints_its_result_then_says_it_was_not_recorded(
    db: Path, full_after: Callable[[int], None], capsys: pytest.CaptureFixture[str]
) -> None:
    full_after(1)  # the run starts; its figures cannot be written
    argv = ("benchmark", "blackjack", "--agent", "optimal", "--episodes", "20", "--db", str(db))
    code, out, err = run_cli(capsys, *argv, "--json")
    assert code == 0 and json.loads(out)["episodes"] == 20
    not_recorded(err)
    code, out, err = run_cli(capsys, *argv)
    assert code == 0 and "Benchmark: blackjack" in out and "recorded as run" not in out
    not_recorded(err)
