"""`tui-gym compare` and `tui-gym sweep`: JSON shapes, records, the chart and table, errors."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rich.console import Console

from tests.test_cli import run
from tui_gym.core.experiments import RunHistory, RunKind
from tui_gym.terminal_chart import BAND, ChartSeries, band_chart


def run_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    code, out, err = run(capsys, *args)
    assert code == 0, err
    (line,) = out.strip().splitlines()
    return json.loads(line)


def test_compare_json_shape_csv_and_records(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    db, csv = tmp_path / "runs.db", tmp_path / "curves.csv"
    data = run_json(
        capsys, "compare", "blackjack", "--algorithms", "q-learning,sarsa", "--seeds", "3",
        "--episodes", "30", "--set", "learning_rate=0.5", "--processes", "0", "--json",
        "--db", str(db), "--csv", str(csv),
    )
    assert (data["game"], data["episodes"], data["seeds"]) == ("blackjack", 30, 3)
    assert [r["algorithm"] for r in data["results"]] == ["q-learning", "sarsa"]
    for result in data["results"]:
        assert result["hyperparameters"]["learning_rate"] == 0.5
        assert isinstance(result["mean_return_last"], float) and result["ci95"] > 0
        # Blackjack has an exact model: its greedy policy's exact value and gap.
        assert result["exact_gap"] == pytest.approx(data["optimum"] - result["exact_value"])
        assert result["exact_gap"] >= 0 and data["optimum"] == pytest.approx(-0.0465558, abs=1e-6)
        assert len(result["curve"]) == 30
        assert [p["episode"] for p in result["curve"]] == list(range(1, 31))
    lines = csv.read_text().splitlines()
    assert lines[0] == ("episode,q-learning.mean,q-learning.lo,q-learning.hi,"
                        "sarsa.mean,sarsa.lo,sarsa.hi")
    assert len(lines) == 31
    with RunHistory(db) as history:
        runs = history.list_runs()
    assert {r.kind for r in runs} == {RunKind.COMPARE} and len(runs) == 2


def test_compare_prints_a_table_and_a_chart(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, out, err = run(
        capsys, "compare", "blackjack", "--algorithms", "q-learning,monte-carlo", "--seeds",
        "2", "--episodes", "20", "--processes", "0", "--no-record",
    )
    assert code == 0, err
    assert "q-learning" in out and "monte-carlo" in out and "95% band" in out
    assert any(0x2800 <= ord(ch) <= 0x28FF for ch in out)  # the braille line
    assert "recorded" not in out


def test_set_fails_clearly_when_no_algorithm_has_it(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "compare", "blackjack", "--algorithms", "q-learning,sarsa",
                         "--set", "planning_steps=5", "--no-record")
    assert code == 2 and out == ""
    assert err.strip() == ("tui-gym: error: no algorithm in the comparison (q-learning, sarsa) "
                           "has 'planning_steps' (planning_steps belongs to dyna-q, dyna-q-plus, "
                           "prioritized-sweeping)")
    code, _, err = run(capsys, "compare", "blackjack", "--algorithms", "q-learning",
                       "--set", "learning_rate", "--no-record")
    assert code == 2 and "expected KEY=VALUE" in err


def test_sweep_json_lists_every_point(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    data = run_json(
        capsys, "sweep", "blackjack", "--algorithm", "sarsa", "--grid", "learning_rate=0.1,0.5",
        "--grid", "discount=0.9,1", "--seeds", "2", "--episodes", "10", "--processes", "0",
        "--json", "--db", str(db),
    )
    assert data["grid"] == {"learning_rate": [0.1, 0.5], "discount": [0.9, 1.0]}
    assert [p["values"] for p in data["points"]] == [
        {"learning_rate": 0.1, "discount": 0.9}, {"learning_rate": 0.1, "discount": 1.0},
        {"learning_rate": 0.5, "discount": 0.9}, {"learning_rate": 0.5, "discount": 1.0},
    ]
    for point in data["points"]:
        assert {"mean_return_last", "ci95", "exact_value", "exact_gap", "curve"} <= set(point)
    with RunHistory(db) as history:
        runs = history.list_runs()
    assert len(runs) == 4 and {r.kind for r in runs} == {RunKind.SWEEP}


def test_sweep_two_keys_show_a_grid(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(
        capsys, "sweep", "blackjack", "--algorithm", "q-learning", "--grid",
        "learning_rate=0.1,0.5", "--grid", "epsilon_final=0,0.1", "--seeds", "2",
        "--episodes", "10", "--processes", "0", "--no-record",
    )
    assert code == 0, err
    assert "learning_rate \\ epsilon_final" in out


def test_sweep_refuses_a_key_the_algorithm_lacks(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, "sweep", "blackjack", "--algorithm", "sarsa", "--grid",
                       "planning_steps=1,2", "--no-record")
    assert code == 2 and "sarsa has no hyperparameter 'planning_steps'" in err


def test_band_chart_draws_lines_bands_and_a_legend() -> None:
    x = np.arange(1, 101)
    up = ChartSeries("up", x, x / 100.0, x / 100.0 - 0.2, x / 100.0 + 0.2)
    flat = ChartSeries("flat", x, np.full(100, 0.5))
    console = Console(width=80, record=True, force_terminal=False)
    console.print(band_chart([up, flat], width=40, height=8))
    text = console.export_text()
    rows = text.splitlines()
    assert "━━ up" in text and "━━ flat" in text and "95% band" in text
    assert any(BAND in row for row in rows)
    # The y range covers the bands (each dot column averages the points in it).
    assert float(rows[0].split()[0]) == pytest.approx(1.2, abs=0.02)
    assert float(rows[7].split()[0]) == pytest.approx(-0.2, abs=0.02)
    assert "100" in rows[-3]  # the last episode on the x axis


def test_first_ctrl_c_asks_to_stop_and_a_second_one_interrupts() -> None:
    import signal
    import threading

    from tui_gym.cli.experiments_command import ctrl_c_stops

    stop = threading.Event()
    with ctrl_c_stops(stop, Console(stderr=True, quiet=True)):
        signal.raise_signal(signal.SIGINT)
        assert stop.is_set()
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)


def test_compare_scores_prediction_learners_by_the_rms_error(
    capsys: pytest.CaptureFixture[str]
) -> None:
    args = ("compare", "random-walk", "--algorithms", "td0,n-step-td", "--seeds", "2",
            "--episodes", "40", "--processes", "0", "--no-record")
    data = run_json(capsys, *args, "--json")
    for result in data["results"]:
        assert result["exact_value"] is None and result["exact_gap"] is None
        assert 0 < result["rms_error"] < 1 and result["rms_ci95"] >= 0
        last = result["rms_curve"][-1]
        assert set(last) == {"episode", "mean", "lo", "hi"} and last["episode"] == 40
        assert last["mean"] == pytest.approx(result["rms_error"])
    code, out, err = run(capsys, *args)
    assert code == 0, err
    assert out.count("RMS error of V") == 2  # the table's column and the second chart
    assert "greedy exact value" not in out


def test_sweep_ranks_prediction_learners_by_the_lowest_rms_error(
    capsys: pytest.CaptureFixture[str]
) -> None:
    args = ("sweep", "random-walk", "--algorithm", "n-step-td", "--grid",
            "learning_rate=0.01,0.1,0.5", "--grid", "n=1,4", "--seeds", "2", "--episodes", "60",
            "--processes", "0", "--no-record")
    data = run_json(capsys, *args, "--json")
    errors = [p["rms_error"] for p in data["points"]]
    assert all(p["exact_value"] is None and p["rms_curve"] for p in data["points"])
    assert [p["rank"] for p in data["points"]] == [sorted(errors).index(e) + 1 for e in errors]
    code, out, err = run(capsys, *args)
    assert code == 0, err
    assert "RMS error of V: learning_rate (rows)" in out  # the grid, the lowest best
