"""How the Compare view lists a run: an app's run whose agent is still there is open,
not running."""

from __future__ import annotations

from pathlib import Path

from tui_gym.core.experiments import RunHistory, RunRecorder, RunSpec
from tui_gym.ui.compare_view import describe_run


def test_an_open_app_run_reads_open_and_a_running_train_run_reads_running(
    tmp_path: Path,
) -> None:
    with RunHistory(tmp_path / "runs.db") as history:
        for kind in ("app", "train", "compare"):
            history.start_run(RunSpec(kind, "blackjack", "q-learning", seeds=(0,)))
        with RunRecorder(history, RunSpec("app", "blackjack", "sarsa", seeds=(0,))):
            pass  # ended: the app let its agent go
        lines = {(run.kind, run.algorithm): describe_run(run).plain
                 for run in history.list_runs()}
    assert " · open in the app · " in lines[("app", "q-learning")]
    assert "running" not in lines[("app", "q-learning")]
    assert " · running · " in lines[("train", "q-learning")]
    assert " · running · " in lines[("compare", "q-learning")]
    assert "open" not in lines[("app", "sarsa")] and "running" not in lines[("app", "sarsa")]
