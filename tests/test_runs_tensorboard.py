"""`tui-gym runs export ID --tensorboard DIR`: event files read back, and the missing extra."""

from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from tui_gym.cli import main
from tui_gym.core.experiments import Curve, Figure, RunHistory, RunKind, RunSpec, RunStatus
from tui_gym.core.experiments.tensorboard import scalar_tag


def read_events(path: Path) -> list:
    """Every event of a TensorBoard event file (length, crc, record, crc; crcs not checked)."""
    from tensorboardX.proto import event_pb2

    data = path.read_bytes()
    events, at = [], 0
    while at < len(data):
        (length,) = struct.unpack("<Q", data[at : at + 8])
        events.append(event_pb2.Event.FromString(data[at + 12 : at + 12 + length]))
        at += 12 + length + 4
    return events


def recorded_run(db: Path) -> int:
    with RunHistory(db) as history:
        run = history.start_run(RunSpec(RunKind.COMPARE, "cliffwalking", "sarsa", seeds=(0, 1)))
        episodes = np.arange(1, 51) * 10
        mean = -100 + np.arange(50, dtype=float)
        history.update(
            run,
            curves=[Curve("return", episodes, mean), Curve("return.lo", episodes, mean - 5),
                    Curve("return.hi", episodes, mean + 5)],
            figures=[Figure("mean_return_last", -52.0, "return", 3.0)],
            status=RunStatus.FINISHED,
        )
    return run


def test_tags_follow_cleanrl() -> None:
    assert scalar_tag("return") == "charts/episodic_return"
    assert scalar_tag("return.lo") == "charts/episodic_return_lo"
    assert scalar_tag("exact_value.hi") == "charts/exact_value_hi"
    assert scalar_tag("win rate") == "charts/win_rate"


def test_export_writes_event_files_tensorboard_reads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("tensorboardX")
    db = tmp_path / "runs.db"
    run = recorded_run(db)
    logdir = tmp_path / "tb"
    for _ in range(2):  # exporting again replaces the earlier file
        assert main(["runs", "export", str(run), "--tensorboard", str(logdir), "--json",
                     "--db", str(db)]) == 0
        done = json.loads(capsys.readouterr().out)
    [event_file] = (logdir / f"run-{run}-cliffwalking-sarsa").glob("events.out.tfevents.*")
    assert done["path"] == str(event_file) and done["scalars"] == 151
    scalars: dict[str, list[tuple[int, float]]] = {}
    for event in read_events(event_file):
        for value in event.summary.value:
            if value.HasField("simple_value"):
                scalars.setdefault(value.tag, []).append((event.step, value.simple_value))
    returns = scalars["charts/episodic_return"]
    assert [step for step, _ in returns] == list(range(10, 510, 10))
    assert [v for _, v in returns] == pytest.approx(list(-100 + np.arange(50.0)), abs=0.1)
    assert scalars["charts/episodic_return_lo"][0] == (10, pytest.approx(-105, abs=0.1))
    assert scalars["figures/mean_return_last"] == [(500, -52.0)]


def test_without_the_extra_one_line_says_how_to_install(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "runs.db"
    run = recorded_run(db)
    monkeypatch.setitem(sys.modules, "tensorboardX", None)  # import fails as if not installed
    code = main(["runs", "export", str(run), "--tensorboard", str(tmp_path / "tb"),
                 "--db", str(db)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "pip install 'tui-gym[tensorboard]'" in err
    assert not (tmp_path / "tb").exists()
