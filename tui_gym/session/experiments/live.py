"""What the run history keeps of a session's training: its settings, curves and figures."""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.engine.trainer import EPISODE_RETURNS
from tui_gym.core.experiments.aggregate import LAST_FRACTION
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.records import Curve, RunKind, RunSpec, WrapperSetting

if TYPE_CHECKING:
    from tui_gym.session.evaluation import EvalReport
    from tui_gym.session.session import Session

# Checkpoints may take this share of the run's time; past it they wait (the first and the
# final one are always taken).
CHECKPOINT_SHARE = 0.01
MAX_CHECKPOINTS = 1000  # beyond this, every other checkpoint is dropped


def run_spec(session: Session, kind: RunKind) -> RunSpec:
    """The session's settings as the run history keeps them."""
    from tui_gym.core.wrappers import get_spec

    assert session.hp is not None  # a built session has its hyperparameters
    return RunSpec(
        kind=kind,
        game=session.game.name,
        algorithm=session.algorithm,
        game_params=dict(session.env_kwargs),
        wrappers=tuple(
            WrapperSetting(c.name, get_spec(c.name).validate(c.values())) for c in session.applied
        ),
        hyperparameters=dict(session.hp),
        seeds=(session.seed,),
    )


def return_curve(snapshot: TrainingSnapshot, after: int = 0) -> Curve | None:
    """The online return per episode (bucket means), of the episodes after `after`."""
    points = snapshot.series.get(EPISODE_RETURNS, ())
    n, recorded = len(points), snapshot.recorded
    if not n or not recorded:
        return None
    # The series keeps `recorded // span` points, span a power of two (see `Series`).
    span = 1
    while recorded // span > n:
        span *= 2
    if recorded // span != n:
        span = max(1, recorded // n)
    first = snapshot.episodes - recorded  # episodes before the statistics began (a loaded agent)
    episodes = first + span * np.arange(1, n + 1, dtype=np.int64)
    keep = episodes > after
    if not keep.any():
        return None
    return Curve("return", episodes[keep], np.asarray(points, dtype=np.float64)[keep])


class ExactCheckpoints:
    """The greedy policy's exact value at checkpoints, for games with an exact model (a
    prediction learner's RMS error of V against the exact values of its policy)."""

    def __init__(self, session: Session) -> None:
        self.session = session
        self.episodes: list[int] = []
        self.values: list[float] = []
        self.available = True  # False: the game has no exact model here
        self.last: dict[str, float] = {}
        self._began = time.perf_counter()
        self._spent = 0.0  # seconds spent on checkpoints

    @property
    def name(self) -> str:
        """The figure the checkpoints follow."""
        return "rms_error" if self.session.predicts else "exact_value"

    def _reference(self, snapshot: TrainingSnapshot | None) -> dict[str, float]:
        if self.session.predicts:
            prediction = self.session.prediction(snapshot)
            return {} if prediction is None else {"rms_error": prediction.rms}
        try:
            ref = self.session.reference(snapshot)
        except (ValueError, KeyError, IndexError):  # a table that does not fit the game now
            return {}
        return {} if ref is None or not ref.scope.exact else dict(ref.figures)

    def take(self, snapshot: TrainingSnapshot | None = None, *, final: bool = False) -> None:
        """A checkpoint at the snapshot's episode (the live agent's when None), unless
        checkpoints have had their share of the time so far; `final` takes it anyway."""
        if not self.available:
            return
        started = time.perf_counter()
        if self.episodes and not final and self._spent > CHECKPOINT_SHARE * (started - self._began):
            return
        episode = self.session.trainer.episodes if snapshot is None else snapshot.episodes
        figures = self._reference(snapshot)
        self._spent += time.perf_counter() - started
        value = figures.get(self.name)
        if value is None or not math.isfinite(value):
            self.available = False
            return
        self.last = figures
        if self.episodes and episode <= self.episodes[-1]:
            self.values[-1] = float(value)  # the same episode again: the newer value
            return
        self.episodes.append(int(episode))
        self.values.append(float(value))
        if len(self.episodes) > MAX_CHECKPOINTS:
            self.episodes, self.values = self.episodes[::2], self.values[::2]

    def curve(self) -> Curve | None:
        if not self.episodes:
            return None
        return Curve(self.name, np.asarray(self.episodes), np.asarray(self.values))


def run_results(
    snapshot: TrainingSnapshot | None, checkpoints: ExactCheckpoints, after: int,
    report: EvalReport | None = None,
) -> tuple[list[Curve], list[Figure]]:
    """What the run history keeps of the episodes after `after` as of `snapshot`: the return
    per episode and the checkpoints' curve; `mean_return_last`, the exact figures known, the
    episodes trained and the greedy evaluation's mean return with its 95% interval."""
    curve = None if snapshot is None else return_curve(snapshot, after)
    curves = [c for c in (curve, checkpoints.curve()) if c is not None]
    exact, figures = checkpoints.last, list[Figure]()
    if curve is not None and len(curve):
        last = int(curve.episodes[-1])
        # The buckets that end within the last 10% of the run's episodes.
        cut = last - math.ceil((last - after) * LAST_FRACTION - 1e-9)
        tail = curve.values[curve.episodes > cut]
        if not len(tail):
            tail = curve.values[-1:]
        figures.append(Figure("mean_return_last", float(np.nanmean(tail)), "return"))
    for key, name, unit in (("exact_value", "exact_value", "return"),
                            ("gap", "exact_gap", "return"), ("rms_error", "rms_error", "")):
        if key in exact:
            figures.append(Figure(name, exact[key], unit))
    if snapshot is not None:
        figures.append(Figure("episodes", max(0, snapshot.episodes - after), "episodes"))
    if report is not None and report.episodes:
        half = 1.96 * report.standard_error if report.episodes > 1 else None
        figures.append(Figure("eval_mean_return", report.mean_return, "return", half))
    return curves, figures
