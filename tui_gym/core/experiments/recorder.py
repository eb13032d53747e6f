"""`RunRecorder`: one run being recorded, from its start to how it ended."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from types import TracebackType

import numpy as np

from tui_gym.core.experiments.aggregate import CurveAccumulator
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.history import STORED_POINTS, RunHistory
from tui_gym.core.experiments.records import Curve, RunSpec, RunStatus


class RunRecorder:
    """Records one run into a `RunHistory`; `run_id` is its id there."""

    def __init__(
        self, history: RunHistory, spec: RunSpec, *, max_points: int = STORED_POINTS,
        first_episode: int = 1,
    ) -> None:
        self.history = history
        self.max_points = max_points
        self.first_episode = first_episode
        self.run_id = history.start_run(spec)
        self.status = RunStatus.RUNNING
        self._accumulators: dict[str, CurveAccumulator] = {}
        self._curves: dict[str, Curve] = {}
        self._figures: dict[str, Figure] = {}
        self._agent_path: str | None = None

    def extend(self, name: str, values: np.ndarray | Iterable[float]) -> None:
        """Append the values of the next episodes to the per-episode curve `name`."""
        accumulator = self._accumulators.get(name)
        if accumulator is None:
            # Twice the stored points, so the stored curve is re-bucketed from finer buckets.
            accumulator = CurveAccumulator(2 * self.max_points, self.first_episode)
            self._accumulators[name] = accumulator
        accumulator.extend(np.asarray(values if isinstance(values, np.ndarray) else list(values)))

    def put_curve(self, curve: Curve) -> None:
        """A whole curve (say, values at checkpoints), replacing any of the same name."""
        self._curves[curve.name] = curve

    def add_figures(self, *figures: Figure) -> None:
        """Final figures, replacing any of the same name."""
        for figure in figures:
            self._figures[figure.name] = figure

    def set_agent_path(self, path: str | Path) -> None:
        """Where the run's agent was saved."""
        self._agent_path = str(path)

    def _pending_curves(self) -> list[Curve]:
        curves = dict(self._curves)
        for name, accumulator in self._accumulators.items():
            if accumulator.count:
                curves[name] = Curve(name, *accumulator.curve(self.max_points))
        return list(curves.values())

    def flush(self, status: RunStatus | None = None) -> None:
        """Write what the run has so far (and `status`, if given) in one transaction."""
        self.history.update(
            self.run_id, curves=self._pending_curves(), figures=list(self._figures.values()),
            agent_path=self._agent_path, status=status, max_points=self.max_points,
        )

    def finish(self, status: RunStatus = RunStatus.FINISHED) -> None:
        """Write everything with the run's final status."""
        self.flush(status)
        self.status = RunStatus(status)

    def __enter__(self) -> RunRecorder:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self.status is not RunStatus.RUNNING:
            return
        if exc_type is None:
            self.finish(RunStatus.FINISHED)
        elif issubclass(exc_type, KeyboardInterrupt):
            self.finish(RunStatus.INTERRUPTED)
        else:
            self.finish(RunStatus.FAILED)
