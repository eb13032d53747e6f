"""Experiments: curves over seeds aggregated into a mean and a confidence band, and the run
history (an SQLite file) that keeps every run with its settings, curves and figures."""

from tui_gym.core.experiments.aggregate import (
    Estimate,
    aggregate,
    mean_return_last,
    mean_with_ci,
    rolling_mean,
)
from tui_gym.core.experiments.errors import (
    DamagedRunError,
    DamagedRunHistoryError,
    NewerRunHistoryError,
    NotARunHistoryError,
    RunHistoryError,
    UnknownRunError,
)
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.history import (
    STORED_POINTS,
    BestEffortHistory,
    DamagedRun,
    RunHistory,
    RunRecorder,
)
from tui_gym.core.experiments.paths import resolve_db_path
from tui_gym.core.experiments.records import (
    Curve,
    RunKind,
    RunRecord,
    RunSpec,
    RunStatus,
    RunSummary,
    Versions,
    WrapperSetting,
)
from tui_gym.core.experiments.runs import (
    export_run_csv,
    list_runs,
    prune_tasks,
    remove_run,
    show_run,
)

__all__ = [
    "STORED_POINTS", "BestEffortHistory", "Curve", "DamagedRun", "DamagedRunError",
    "DamagedRunHistoryError", "Estimate", "Figure", "NewerRunHistoryError", "NotARunHistoryError",
    "RunHistory", "RunHistoryError", "RunKind", "RunRecord", "RunRecorder", "RunSpec", "RunStatus",
    "RunSummary", "UnknownRunError", "Versions", "WrapperSetting", "aggregate", "export_run_csv",
    "list_runs", "mean_return_last", "mean_with_ci", "prune_tasks", "remove_run",
    "resolve_db_path", "rolling_mean", "show_run",
]
