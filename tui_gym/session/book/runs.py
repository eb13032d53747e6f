"""Figures that run learners over seeds: what a run figure declares, plays, draws and checks."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from tui_gym.algorithms import Predictor, algorithm
from tui_gym.algorithms.prediction import rms_curve
from tui_gym.core.engine import loop
from tui_gym.core.engine.loop import FIRST_ACTION, LENGTH, RETURN
from tui_gym.core.experiments.aggregate import aggregate, t_half_width
from tui_gym.core.experiments.records import RunKind
from tui_gym.core.mdp import NotAvailable, Phases
from tui_gym.games import game_named
from tui_gym.games.base import TrainingModel
from tui_gym.games.model import ModelGame
from tui_gym.session.book.figure import (
    BookFigure,
    Check,
    FigureOptions,
    FigureStopped,
    FigureTasks,
    Progress,
    Series,
    heading,
)
from tui_gym.session.experiments.compare import (
    Arm,
    CompareProgress,
    Setup,
    execute,
    prepare,
    resumed_group,
)

__all__ = [
    "BANDS", "FIRST_ACTION", "LENGTH", "RETURN", "Played", "above", "below", "book_settings",
    "completed", "counts", "margin", "near", "per_episode", "per_time_step", "play",
    "play_prediction", "play_steps", "swept", "world_phases",
]

CHECK_CONFIDENCE = 0.99  # the verdicts' intervals
BANDS = "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"  # a figure's note
Samples = npt.ArrayLike


def book_settings(discount: float, epsilon: float = 0.1, **more: Any) -> dict[str, Any]:
    """The book's control settings: a constant ε and step size, `discount`, and `more`."""
    return {"learning_rate_schedule": "constant", "discount": discount,
            "epsilon_start": epsilon, "epsilon_final": epsilon, **more}


@dataclass(frozen=True, eq=False)
class Played:
    """A learner's runs: `values[run, episode]`, and `final[run]`, its greedy policy's exact
    value at the end (None without a model)."""

    label: str
    values: np.ndarray
    final: np.ndarray | None
    optimum: float | None

    @property
    def runs(self) -> int:
        return int(self.values.shape[0])


def counts(figure: BookFigure, options: FigureOptions) -> tuple[int, int]:
    """(runs, episodes): the flags', else the figure's defaults (or its full counts)."""
    runs = options.runs or (figure.full_runs if options.full else None) or figure.runs or 1
    episodes = (options.episodes or (figure.full_episodes if options.full else None)
                or figure.episodes or 1)
    return runs, episodes


def play(figure: BookFigure, world: str, learners: Sequence[Arm], options: FigureOptions,
         progress: Progress, *, measure: int = RETURN,
         game_params: Mapping[str, Any] | None = None, runs: int | None = None,
         episodes: int | None = None) -> list[Played]:
    """Every learner over the figure's runs, as a comparison's tasks; `runs` and `episodes`
    override `counts(figure, options)`."""
    counted = counts(figure, options)
    runs, episodes = runs or counted[0], episodes or counted[1]
    setup = Setup(world, runs, episodes, dict(game_params or {}), (), options.seed, measure)
    names = ", ".join(x.label for x in learners) if len(learners) <= 4 else (
        f"{len(learners)} learners")
    about = f"{runs:,} runs × {episodes:,} episodes of {names}"
    tasks = options.tasks or FigureTasks()

    def told(state: CompareProgress) -> None:
        progress(state.done, state.total, about + (
            f" ({tasks.landed + state.tasks_done}/{tasks.tasks + state.tasks_total} tasks)"
            if options.tasks else ""))

    resume = None  # the runs of `tasks.resume`'s group this play carries on
    if tasks.resume is not None and tasks.history is not None:
        ids = resumed_group(tasks.history, tasks.resume, "figure")
        tasks.group = tasks.resume
        resume = ids[tasks.played: tasks.played + len(learners)] or None
    done = execute(setup, learners, RunKind.COMPARE, progress=told, stop=options.stop,
                   status=lambda line: progress(0, 1, line or about), history=tasks.history,
                   resume=resume, cluster=tasks.cluster, group=tasks.group)
    tasks.group = tasks.group or done.group
    tasks.played += len(learners)
    tasks.tasks += done.tasks.get("total", 0)
    tasks.landed += done.tasks.get("done", 0)
    if done.interrupted:
        raise FigureStopped(f"{heading(figure.name)} stopped")
    return [Played(learner.label, done.values[index],
                   None if done.exact is None else done.exact[index, :, -1].copy(),
                   done.prepared.optimum)
            for index, learner in enumerate(learners)]


def play_steps(figure: BookFigure, world: str, learners: Sequence[Arm],
               options: FigureOptions, progress: Progress, steps: int, *,
               game_params: Mapping[str, Any] | None = None) -> list[Played]:
    """Every learner over the figure's runs of `steps` time steps, phase after phase:
    `values[run, t]`, the returns of the episodes finished in the first t + 1 steps."""
    runs, _ = counts(figure, options)
    setup = Setup(world, runs, 1, dict(game_params or {}), (), options.seed)
    prepared = prepare(setup, learners)
    phases = world_phases(world, prepared.env_kwargs)
    arrays = [loop.ModelArrays.of(model) for model in phases.models]
    ends = [*phases.starts[1:], steps]
    n_states, n_actions = phases.models[0].n_states, phases.models[0].n_actions
    about = f"{runs} runs × {steps} time steps of {', '.join(x.label for x in learners)}"
    played = []
    for index, (learner, hp) in enumerate(zip(learners, prepared.hyperparameters, strict=True)):
        cls = algorithm(learner.algorithm)
        values = np.zeros((runs, steps))
        for run in range(runs):
            options.check_stop(figure.name)
            at = index * runs + run
            progress(at, len(learners) * runs, about)
            agent = cls(n_actions, cls.settings(hp), n_states=n_states, seed=options.seed + run)
            loop.warm([(agent.name, agent.arrays(), agent.compiled_params())],
                      functools.partial(progress, at, len(learners) * runs))
            values[run] = _cumulative_reward(agent, arrays, phases.starts, ends, steps)
        played.append(Played(learner.label, values, None, None))
    progress(len(learners) * runs, len(learners) * runs, about)
    return played


def play_prediction(figure: BookFigure, states: int, learners: Sequence[Arm],
                    options: FigureOptions, progress: Progress) -> list[Played]:
    """Every prediction learner over the figure's runs on the random walk of `states`
    states: `values[run, episode]`, the RMS error of V after each episode."""
    runs, episodes = counts(figure, options)
    game = game_named("random-walk")
    found = game.training_model(game.normalize_kwargs({"states": states}))
    assert isinstance(found, TrainingModel)
    model = loop.ModelArrays.of(found.model)
    about = f"{runs} runs × {episodes} episodes of {len(learners)} learners"
    played = []
    for index, learner in enumerate(learners):
        progress(index, len(learners), about)
        cls = algorithm(learner.algorithm)
        assert issubclass(cls, Predictor)
        values = np.empty((runs, episodes))
        settings = cls.settings(learner.settings)
        truth = None
        for run in range(runs):
            options.check_stop(figure.name)
            agent = cls(found.model.n_actions, settings, n_states=found.model.n_states,
                        seed=options.seed + run)
            truth = truth or agent.truth(found.model)  # one policy: the random one
            values[run] = rms_curve(agent, model, truth, episodes)
        played.append(Played(learner.label, values, None, None))
    progress(len(learners), len(learners), about)
    return played


def world_phases(world: str, kwargs: Mapping[str, Any]) -> Phases:
    """The model of each phase of the game `world` (ValueError for a game without one)."""
    game = game_named(world)
    phases = (game.world(kwargs, game.own_changes(kwargs)) if isinstance(game, ModelGame)
              else NotAvailable("it has no exact model"))
    if isinstance(phases, NotAvailable):
        raise ValueError(f"{world} has no model to play: {phases.reason}")
    return phases


def _cumulative_reward(agent: Any, arrays: Sequence[loop.ModelArrays], starts: Sequence[int],
                       ends: Sequence[int], steps: int) -> np.ndarray:
    """One learner's cumulative reward after each of `steps` time steps, phase by phase."""
    cursor, log = loop.Cursor(), np.zeros((1, 8))
    out = np.zeros((4096, loop.COLUMNS))
    returns, lengths = [], []
    for model, start, end in zip(arrays, starts, ends, strict=False):
        at = max(start, 0)
        while at < min(end, steps):
            done, played = loop.play(agent, model, cursor, len(out), min(end, steps) - at, out, log)
            returns.append(out[:done, RETURN].copy())
            lengths.append(out[:done, LENGTH].copy())
            at += played
    paid = np.zeros(steps + 1)
    finished = np.cumsum(np.concatenate(lengths)).astype(np.int64)  # the step each ended at
    np.add.at(paid, finished, np.concatenate(returns))
    return np.cumsum(paid)[1:]


def margin(samples: Samples) -> float:
    """The half-width of the 99% Student-t interval of the mean (NaN for one sample)."""
    values = np.asarray(samples, dtype=np.float64).ravel()
    if len(values) < 2:
        return math.nan
    return float(t_half_width(values.std(ddof=1), len(values), CHECK_CONFIDENCE))


def _within(mean: float, tolerance: float, digits: int, unit: str) -> str:
    if math.isnan(tolerance):
        return f"{mean:.{digits}f}{unit} (one run: no interval)"
    return f"{mean:.{digits}f}{unit} ± {tolerance:.{digits}f}"


def near(claim: str, book: float, samples: Samples, slack: float = 0.0, digits: int = 1,
         unit: str = "", one_run: bool = False) -> Check:
    """The mean of `samples` (one a run) within `slack` + `margin(samples)` of `book`; with
    `one_run` (`book` read off a figure of one run), + the 99% prediction interval instead."""
    values = np.asarray(samples, dtype=np.float64).ravel()
    spread = margin(values) * (np.sqrt(len(values) + 1) if one_run else 1.0)
    mean, tolerance = float(values.mean()), slack + spread
    return Check(claim, f"{book:g}{unit}" + " (one run)" * one_run,
                 _within(mean, tolerance, digits, unit), abs(mean - book) <= tolerance)


def below(claim: str, book: str, lower: Samples, higher: Samples, digits: int = 1,
          unit: str = "") -> Check:
    """`above` for a claim whose subject is the lower one (measured: its mean first)."""
    return above(claim, book, higher, lower, digits, unit, lower_first=True)


def above(claim: str, book: str, higher: Samples, lower: Samples, digits: int = 1,
          unit: str = "", lower_first: bool = False) -> Check:
    """The mean of `higher` above that of `lower` by more than the margin of the difference."""
    a = np.asarray(higher, dtype=np.float64).ravel()
    b = np.asarray(lower, dtype=np.float64).ravel()
    gap = float(a.mean() - b.mean())
    spread = float(np.hypot(margin(a), margin(b)))
    means = [f"{x.mean():.{digits}f}{unit}" for x in ((b, a) if lower_first else (a, b))]
    measured = " vs ".join(means)
    if len(a) < 2:
        measured += " (one run: no interval)"
    return Check(claim, book, measured, gap > spread)


def per_episode(played: Played, window: int = 1, points: int | None = None) -> Series:
    """The mean over runs of each episode's (or time step's) measure with its band, each
    run smoothed over a trailing `window` first, at most `points` of them."""
    curve = aggregate(played.values, window=window, max_points=points)
    return Series(played.label, curve.episodes.astype(np.float64), curve.mean, curve.lo, curve.hi)


def completed(played: Played, steps: npt.ArrayLike) -> np.ndarray:
    """`[run, i]`: the episodes each run completed by time step `steps[i]` (of `LENGTH`)."""
    ends = np.cumsum(played.values, axis=1)  # the time step each episode ended at, per run
    return np.stack([np.searchsorted(row, steps, side="right") for row in ends]).astype(float)


def per_time_step(played: Played, points: int = 200, until: float | None = None) -> Series:
    """Episodes completed against time steps (of `LENGTH`), up to `until` or where every
    run reached."""
    last = float(played.values.sum(axis=1).min())
    last = last if until is None else min(last, until)
    steps = np.unique(np.linspace(0, last, points).round())
    curve = aggregate(completed(played, steps), episodes=steps.astype(np.int64))
    return Series(played.label, steps, curve.mean, curve.lo, curve.hi)


def swept(label: str, xs: Sequence[float], played: Sequence[Played],
          summary: Callable[[np.ndarray], np.ndarray],
          shown: tuple[float, float] = (-math.inf, math.inf)) -> Series:
    """One point per learner of a sweep, the mean of `summary(values)` over runs with its
    band; only points with a finite band and a mean within `shown` are kept."""
    ys, los, his = [], [], []
    for one in played:
        per_run = np.asarray(summary(one.values), dtype=np.float64)
        mean = float(per_run.mean())
        half = (float(t_half_width(per_run.std(ddof=1), len(per_run))) if len(per_run) > 1 else 0.0)
        ys.append(mean)
        los.append(mean - half)
        his.append(mean + half)
    x, y, lo, hi = (np.asarray(v, dtype=np.float64) for v in (xs, ys, los, his))
    keep = np.isfinite(hi) & (shown[0] <= y) & (y <= shown[1])
    return Series(label, x[keep], y[keep], lo[keep], hi[keep])
