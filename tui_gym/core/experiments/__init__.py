"""Experiments: curves over seeds aggregated into a mean and a confidence band, and the run
history (an SQLite file) that keeps every run with its settings, curves and figures."""

from tui_gym.core.experiments.aggregate import (
    AggregateCurve,
    CurvePoint,
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
    RunHistoryBusyError,
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
    RunRows,
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
from tui_gym.core.experiments.recover import Recovery
from tui_gym.core.experiments.runs import (
    CsvExport,
    PrunedTasks,
    RemovedRun,
    RunListing,
    export_run_csv,
    list_runs,
    prune_tasks,
    recover_history,
    remove_run,
    show_run,
)

__all__ = [
    "STORED_POINTS", "AggregateCurve", "BestEffortHistory", "CsvExport", "Curve", "CurvePoint",
    "DamagedRun", "DamagedRunError", "DamagedRunHistoryError", "Estimate", "Figure",
    "NewerRunHistoryError", "NotARunHistoryError", "Recovery", "PrunedTasks", "RemovedRun",
    "RunHistory", "RunHistoryBusyError", "RunHistoryError", "RunKind", "RunListing", "RunRecord",
    "RunRecorder", "RunRows", "RunSpec", "RunStatus", "RunSummary", "UnknownRunError", "Versions",
    "WrapperSetting", "aggregate", "export_run_csv", "list_runs", "mean_return_last",
    "mean_with_ci", "recover_history", "prune_tasks", "remove_run", "resolve_db_path",
    "rolling_mean", "show_run",
]
