"""The run history stays small: a thousand runs with a few curves each under 1 MB."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tui_gym.core.experiments import (
    STORED_POINTS,
    Curve,
    Figure,
    RunHistory,
    RunKind,
    RunSpec,
    RunStatus,
    WrapperSetting,
)

RUNS = 1000
POINTS = 500
BUDGET = 1_000_000  # bytes


def test_a_thousand_runs_fit_in_a_megabyte(tmp_path: Path) -> None:
    path = tmp_path / "runs.db"
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, POINTS)
    hyperparameters = {
        "learning_rate": 0.01,
        "discount": 0.95,
        "epsilon_start": 1.0,
        "epsilon_final": 0.1,
        "epsilon_decay_fraction": 0.5,
        "episodes": 200_000,
    }
    with RunHistory(path) as history:
        for seed in range(RUNS):
            run_spec = RunSpec(
                kind=RunKind.TRAIN,
                game="blackjack",
                algorithm="q_learning",
                game_params={"sab": False, "natural": False},
                wrappers=(WrapperSetting("TimeLimit", {"max_episode_steps": 100}),),
                hyperparameters=hyperparameters,
                seeds=(seed,),
            )
            run_id = history.start_run(run_spec)
            # Noisy learning curves, one point per 400 episodes, as a default run's.
            episodes = np.arange(1, POINTS + 1) * 400
            noise = rng.standard_normal((3, POINTS))
            history.update(
                run_id,
                curves=[
                    Curve("return", episodes, -0.05 - 0.5 * np.exp(-5 * t) + 0.05 * noise[0]),
                    Curve("length", episodes, 1.5 + 0.3 * np.exp(-4 * t) + 0.03 * noise[1]),
                    Curve("td_error", episodes, 0.02 + 0.3 * np.exp(-3 * t) + 0.01 * noise[2]),
                ],
                figures=[
                    Figure("mean_return_last", -0.0512, "return", 0.0031),
                    Figure("exact_value", -0.0498, "return"),
                    Figure("exact_gap", 0.0032, "return"),
                ],
                status=RunStatus.FINISHED,
            )
        assert len(history.list_runs()) == RUNS
        assert len(history.get_run(run_id).curves[0]) == STORED_POINTS
    # Closing the last connection folds the write-ahead log into the file.
    assert not Path(f"{path}-wal").exists()
    assert path.stat().st_size < BUDGET
