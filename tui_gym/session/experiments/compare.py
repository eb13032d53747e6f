"""Comparisons: several algorithms on one game, each over many seeds, aggregated and recorded."""

from __future__ import annotations

import contextlib
import functools
import json
import os
import queue
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tui_gym.algorithms import ALGORITHMS, Predictor, algorithm
from tui_gym.core.engine import processes as processes_module
from tui_gym.core.engine.loop import FIRST_ACTION, LENGTH, RETURN, ModelArrays, warm
from tui_gym.core.engine.seeds import checkpoint_episodes, greedy_values, play_learner
from tui_gym.core.experiments.aggregate import (
    AggregateCurve,
    CurvePoint,
    Estimate,
    aggregate,
    mean_return_last,
    mean_with_ci,
)
from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.figures import Figure, plain
from tui_gym.core.experiments.history import STORED_POINTS, RunHistory
from tui_gym.core.experiments.records import RunKind, RunSpec, RunStatus, TaskRecord, WrapperSetting
from tui_gym.core.mdp import FiniteMDP, solve
from tui_gym.core.text import visible
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.experiments.live import run_spec

__all__ = [
    "JSON_CURVE_POINTS", "RESUME_ADVICE", "AlgorithmOutcome", "CompareError", "CompareProgress",
    "CompareResult", "CompareSpec", "ResumeError", "SeedsUpdate", "run_compare",
]

PROGRESS_INTERVAL = 0.4  # seconds between progress calls
JSON_CURVE_POINTS = 500  # curve points in `to_json`
SPREAD_SECONDS = 1.0  # work that takes longer than this here is spread over child processes
# A task process ends after this many seeds and another takes over: Numba keeps every
# learner's random generator it was called with (numba/numba#9103), a few kB a seed.
WORKER_SEEDS = 2000
PROBE_SECONDS = 0.1  # how long throwaway learners play to tell how long the work is
SMOOTHING_SHARE = 50  # charts smooth each seed's returns over 1/50 of the episodes
TASK_SECONDS = 1.0  # a task (a block of one arm's seeds) runs about this long at least
RESUME_ADVICE = "; give the command that started it to resume it"  # ends ResumeError's lines


@dataclass(frozen=True)
class CompareSpec:
    """What to compare: `algorithms` on `game`, `seeds` seeds from `first_seed`, `episodes` each;
    `settings` go to every algorithm that has them (the budget `episodes` defaults to these)."""

    game: str
    algorithms: Sequence[str]
    seeds: int
    episodes: int
    settings: Mapping[str, Any] = field(default_factory=dict)
    game_params: Mapping[str, Any] = field(default_factory=dict)
    wrappers: Sequence[WrapperChoice] = ()
    first_seed: int = 0

    def __post_init__(self) -> None:
        names = tuple(algorithm(a).name for a in self.algorithms)
        if not names:
            raise ValueError("a comparison needs at least one algorithm")
        duplicate = next((n for n in names if names.count(n) > 1), None)
        if duplicate:
            raise ValueError(f"algorithm {duplicate} is listed twice")
        object.__setattr__(self, "algorithms", names)
        settle_runs(self)
        unknown = [k for k in self.settings if not _owners(k, names)]
        if unknown:
            raise ValueError(
                f"no algorithm in the comparison ({', '.join(names)}) has "
                + ", ".join(repr(k) for k in unknown)
                + _known_elsewhere(unknown)
            )


def settle_runs(spec: Any) -> None:
    """Check a spec's `seeds` and `episodes`; copy its settings, game parameters and wrappers."""
    for name, value in (("seeds", spec.seeds), ("episodes", spec.episodes)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    object.__setattr__(spec, "settings", dict(spec.settings))
    object.__setattr__(spec, "game_params", dict(spec.game_params))
    object.__setattr__(spec, "wrappers", tuple(spec.wrappers))


def _owners(key: str, names: Sequence[str]) -> list[str]:
    return [n for n in names if any(f.name == key for f in algorithm(n).params)]


def _known_elsewhere(keys: Sequence[str]) -> str:
    owners = {key: _owners(key, [cls.name for cls in ALGORITHMS]) for key in keys}
    notes = [f"{key} belongs to {', '.join(names)}" for key, names in owners.items() if names]
    return f" ({'; '.join(notes)})" if notes else ""


@dataclass(frozen=True, eq=False)
class AlgorithmOutcome:
    """One algorithm's results over its seeds so far (`seeds_done` finished, run `run_id`):
    the mean online return per episode every seed finished (`curve`), and at the checkpoints
    every seed reached the greedy policy's exact value and gap, or a prediction learner's
    RMS error of V."""

    algorithm: str
    hyperparameters: Mapping[str, Any]
    seeds_done: int
    curve: AggregateCurve
    mean_return_last: Estimate
    run_id: int | None
    exact_value: float | None = None
    exact_gap: float | None = None
    exact_curve: AggregateCurve | None = None
    exact_ci95: float | None = None
    seeds: int = 0
    smoothed: AggregateCurve | None = None  # each seed's trailing mean over `smoothing` episodes
    smoothing: int = 1
    rms_error: float | None = None
    rms_ci95: float | None = None
    rms_curve: AggregateCurve | None = None

    @property
    def episodes(self) -> int:
        """Episodes every seed has finished."""
        return int(self.curve.episodes[-1]) if len(self.curve) else 0

    def figures(self) -> tuple[Figure, ...]:
        known = (("exact_value", self.exact_value, self.exact_ci95),
                 ("exact_gap", self.exact_gap, None), ("rms_error", self.rms_error, self.rms_ci95))
        return (self.mean_return_last.figure("mean_return_last"),
                *(Figure(name, value, ci95=ci) for name, value, ci in known if value is not None))

    def to_json(self, max_points: int = JSON_CURVE_POINTS) -> dict[str, Any]:
        def points(curve: AggregateCurve | None) -> list[CurvePoint] | None:
            return None if curve is None else curve.downsample(max_points).points()

        return dict(plain({
            "algorithm": self.algorithm, "hyperparameters": self.hyperparameters,
            "seeds_done": self.seeds_done, "episodes_done": self.episodes,
            "mean_return_last": self.mean_return_last.mean, "ci95": self.mean_return_last.ci95,
            "exact_value": self.exact_value, "exact_gap": self.exact_gap,
            "rms_error": self.rms_error, "rms_ci95": self.rms_ci95,
            "rms_curve": points(self.rms_curve), "run_id": self.run_id,
            "curve": points(self.curve)}))


@dataclass(frozen=True)
class CompareProgress:
    """Episodes and tasks finished of the totals, and each arm's outcome so far
    (`outcomes`, aggregated when first read: read it in the callback)."""

    done: int
    total: int
    tasks_done: int = 0
    tasks_total: int = 0
    outcomes_of: Callable[[], tuple[AlgorithmOutcome, ...]] = field(
        default=tuple, repr=False, compare=False)

    @functools.cached_property
    def outcomes(self) -> tuple[AlgorithmOutcome, ...]:
        return self.outcomes_of()


@dataclass(frozen=True)
class CompareResult:
    """Every algorithm's outcome; `interrupted` when stopped early; `group` the first run's id."""

    outcomes: tuple[AlgorithmOutcome, ...]
    interrupted: bool
    group: int | None
    spec: CompareSpec
    game: str
    optimum: float | None = None
    tasks: Mapping[str, int] = field(default_factory=dict)  # "done" and "total"

    def to_json(self) -> dict[str, Any]:
        spec = self.spec
        return {
            "game": self.game, "episodes": spec.episodes, "seeds": spec.seeds,
            "first_seed": spec.first_seed, "optimum": plain(self.optimum),
            "interrupted": self.interrupted, "group": self.group, "tasks": dict(self.tasks),
            "results": [o.to_json() for o in self.outcomes],
        }


@dataclass(frozen=True)
class Arm:
    """One learner of an experiment: an algorithm with the settings given for it."""

    algorithm: str
    settings: Mapping[str, Any]
    label: str = ""


@dataclass(frozen=True)
class Setup:
    """What every arm of an experiment shares: the game, its seeds and episodes, and the
    per-episode `measure` recorded (`loop.RETURN`, `loop.LENGTH` or `loop.FIRST_ACTION`)."""

    game: str
    seeds: int
    episodes: int
    game_params: Mapping[str, Any]
    wrappers: tuple[WrapperChoice, ...]
    first_seed: int
    measure: int = RETURN

    @property
    def seed_list(self) -> tuple[int, ...]:
        return tuple(range(self.first_seed, self.first_seed + self.seeds))


@dataclass(frozen=True, eq=False)
class _Model:
    """The game's model for the jobs: the loop's arrays, the MDP and its states' table
    rows, the learners' table shape and the actions each row offers (None: all)."""

    arrays: ModelArrays
    mdp: FiniteMDP
    rows: np.ndarray
    n_states: int
    n_actions: int
    offered: np.ndarray | None = None

    def learner(self, name: str, hp: Mapping[str, Any], seed: int | None) -> Any:
        """A new learner of algorithm `name` for this model."""
        cls = algorithm(name)
        learner = cls(self.n_actions, cls.settings(hp), n_states=self.n_states, seed=seed)
        learner.offer(self.offered)
        return learner

    def greedy_values(self, tables: np.ndarray) -> np.ndarray:
        """Exact values of the greedy policies of `tables[m, rows, A]` (among actions offered)."""
        q = tables[:, self.rows]
        if self.offered is not None:
            q = np.where(self.offered[self.rows], q, -np.inf)
        return greedy_values(self.mdp, q)


@dataclass(frozen=True)
class _Job:
    """Seeds `seeds` (rows `rows` of the seed list) of arm `arm`, on the game as `prepared`."""

    index: int
    arm: int
    algorithm: str
    hp: Mapping[str, Any]
    seeds: tuple[int, ...]
    rows: tuple[int, ...]
    setup: Setup
    prepared: Prepared


@dataclass(frozen=True)
class SeedsUpdate:
    """What a job played since its last update: per seed, its episodes done, the returns of
    episodes `first[i]` to `done[i] - 1`, and `exact` as in `TaskRecord` (NaN until reached)."""

    done: np.ndarray
    first: np.ndarray
    returns: tuple[np.ndarray, ...]
    exact: np.ndarray | None


@dataclass
class Prepared:
    """The game as built once: its name, id, arguments, arms' hyperparameters, model, optimum."""

    game: str
    env_id: str
    env_kwargs: dict[str, Any]
    wrappers: Sequence[WrapperSetting]
    hyperparameters: list[dict[str, Any]]
    model: _Model | None
    optimum: float | None


def _session(
    env_id: str, env_kwargs: Mapping[str, Any], wrappers: Sequence[WrapperChoice], name: str,
    hp: Mapping[str, Any], seed: int,
) -> Any:
    from tui_gym.session.session import Session

    return Session(
        env_id=env_id, env_kwargs=dict(env_kwargs), choices=tuple(wrappers), hp=dict(hp),
        seed=seed, algorithm=name,
    )


def prepare(setup: Setup, arms: Sequence[Arm]) -> Prepared:
    """Build the game once per algorithm: checks every arm's settings, and gives the
    hyperparameters (the budget `episodes` defaults to the experiment's). ValueError for a
    bad one."""
    from tui_gym.session.session import default_settings

    hyperparameters: list[dict[str, Any]] = []
    first: Any = None
    built: set[str] = set()
    for arm in arms:
        hp = {"episodes": setup.episodes, **arm.settings}
        if arm.algorithm in built:  # the same learner, other settings: no game to build
            settings = default_settings(first.game, arm.algorithm, first.env_kwargs)
            hyperparameters.append(dict(settings.replace(**hp)))
            continue
        session = _session(setup.game, setup.game_params, setup.wrappers, arm.algorithm, hp,
                           setup.first_seed)
        built.add(arm.algorithm)
        hyperparameters.append(dict(session.hp))
        first = first or session
        if session is not first:
            session.env.close()
    model = optimum = None
    training = first.training
    # A world that changes plays each seed through its session's trainer (`_play_env`),
    # which follows the phases.
    if training is not None and first.trainer.model is not None and len(first.trainer.phases) == 1:
        model = _Model(first.trainer.model, training.model, np.asarray(training.rows),
                       int(first.keyer.n_states), int(first.agent.n_actions),
                       first.agent.offered)
        optimum = plain(solve(training.model).value)
    prepared = Prepared(
        game=first.game.name, env_id=first.env_id, env_kwargs=dict(first.env_kwargs),
        wrappers=run_spec(first, RunKind.COMPARE).wrappers, hyperparameters=hyperparameters,
        model=model, optimum=optimum)
    first.env.close()
    return prepared


def _jobs(setup: Setup, arms: Sequence[Arm], prepared: Prepared,
          missing: Sequence[Sequence[int]], pieces: int = 1) -> list[_Job]:
    """The tasks: each arm's `missing` seed rows in `pieces` blocks of about the same size
    (a seed's run is its own, so the split changes no figure)."""
    seeds = setup.seed_list
    jobs: list[_Job] = []
    for a, arm in enumerate(arms):
        rows = list(missing[a])
        for block in np.array_split(np.asarray(rows, dtype=np.int64),
                                    max(1, min(pieces, len(rows)))):
            if block.size:
                jobs.append(_Job(
                    index=-1, arm=a, algorithm=arm.algorithm, hp=prepared.hyperparameters[a],
                    seeds=tuple(seeds[r] for r in block), rows=tuple(int(r) for r in block),
                    setup=setup, prepared=prepared))
    return jobs


def _run_job(
    job: _Job, stop: Callable[[], bool], report: Callable[[SeedsUpdate], None],
) -> SeedsUpdate:
    """Train a job's seeds in turn, `report`ing what they play as they go; the last update."""
    n, episodes = len(job.seeds), job.setup.episodes
    checkpoints = checkpoint_episodes(episodes)
    done = np.zeros(n, dtype=np.int64)
    returns = np.full((n, episodes), np.nan)
    model = job.prepared.model
    exact = None if model is None else np.full((n, len(checkpoints)), np.nan)

    sent = np.zeros(n, dtype=np.int64)

    def state() -> SeedsUpdate:
        first = sent.copy()
        sent[:] = done
        news = tuple(returns[i, first[i] : done[i]].copy() for i in range(n))
        return SeedsUpdate(done.copy(), first, news, None if exact is None else exact.copy())

    last = [time.monotonic()]

    def counted(i: int, played: int) -> None:
        done[i] = played
        if time.monotonic() - last[0] >= PROGRESS_INTERVAL / 2:
            report(state())
            last[0] = time.monotonic()

    for i, seed in enumerate(job.seeds):
        if stop():
            break
        counter = functools.partial(counted, i)
        if model is not None:
            learner = model.learner(job.algorithm, job.hp, seed)
            _, tables = play_learner(learner, model.arrays, episodes, checkpoints, stop,
                                     returns[i], counter, job.setup.measure)
            if tables and exact is not None:
                found = np.stack(tables)
                exact[i, : len(tables)] = (_rms_errors(learner, model, found)
                                           if isinstance(learner, Predictor)
                                           else model.greedy_values(found))
        else:
            _play_env(job, seed, returns[i], counter, stop)
    return state()


def _rms_errors(learner: Predictor, model: _Model, tables: np.ndarray) -> np.ndarray:
    """Per table (`[m, rows, A]`, V in every action), the RMS error of V against the exact
    values of the policy `learner` follows; NaN where that policy has none."""
    try:
        truth = learner.truth(model.mdp, model.rows)
    except ValueError:
        return np.full(len(tables), np.nan)
    return np.array([truth.rms(table[model.rows, 0]) for table in tables])


def _play_env(job: _Job, seed: int, returns: np.ndarray, progress: Callable[[int], None],
              stop: Callable[[], bool]) -> None:
    """One seed through its session's trainer, an episode at a time: on the Gymnasium env
    (games no model follows), or on a world that changes, phase after phase."""
    measure, prepared = job.setup.measure, job.prepared
    session = _session(prepared.env_id, prepared.env_kwargs, job.setup.wrappers, job.algorithm,
                       job.hp, seed)
    try:
        for e in range(job.setup.episodes):
            if stop():
                return
            stats = session.trainer.run_episode()
            returns[e] = (stats.length if measure == LENGTH else stats.first_action
                          if measure == FIRST_ACTION else stats.episode_return)
            progress(e + 1)
    finally:
        session.env.close()


def run_task(job: _Job) -> list[SeedsUpdate]:
    """A whole task at once (what a cluster's worker runs): its updates, in order."""
    updates: list[SeedsUpdate] = []
    updates.append(_run_job(job, lambda: False, updates.append))
    return updates


def _worker(parent: int, jobs: Mapping[int, _Job], numbers: Any, messages: Any,
            stop_flag: Any) -> None:
    """A child process's work: the jobs numbered on `numbers` until a None, a stop or
    `WORKER_SEEDS` seeds, each one's start and states sent on `messages`."""
    processes_module.watch_parent(parent)
    played = 0
    while played < WORKER_SEEDS and not stop_flag.is_set():
        index = numbers.get()
        if index is None:
            return
        messages.put(("begin", index, None))

        def report(update: SeedsUpdate, index: int = index) -> None:
            messages.put(("state", index, update))

        try:
            final = _run_job(jobs[index], stop_flag.is_set, report)
        except Exception as exc:  # noqa: BLE001 - sent to the parent, which says it in one line
            messages.put(("error", index, f"{type(exc).__name__}: {exc}"))
            return
        messages.put(("end", index, final))
        played += len(jobs[index].seeds)


class _Tally:
    """The jobs' latest states, merged per arm."""

    def __init__(self, setup: Setup, arms: Sequence[Arm], prepared: Prepared) -> None:
        self.setup = setup
        self.arms = arms
        self.prepared = prepared
        self.jobs: list[_Job] = []
        self.run_ids: list[int | None] = [None] * len(arms)
        shape = (len(arms), setup.seeds)
        self.checkpoints = checkpoint_episodes(setup.episodes)
        self.done = np.zeros(shape, dtype=np.int64)
        self.returns = np.full((*shape, setup.episodes), np.nan)
        self.exact = None if prepared.model is None else np.full(
            (*shape, len(self.checkpoints)), np.nan)
        self.tasks_done = 0
        self.tasks_total = 0
        self.predicts = [issubclass(algorithm(arm.algorithm), Predictor) for arm in arms]

    def load(self, arm: int, task: TaskRecord) -> None:
        """Count in a stored task of arm `arm`."""
        rows = list(task.rows)
        self.returns[arm, rows] = task.returns
        self.done[arm, rows] = task.episodes
        if self.exact is not None and task.exact is not None:
            self.exact[arm, rows] = task.exact
        self.tasks_done += 1
        self.tasks_total += 1

    def missing(self) -> list[list[int]]:
        """Each arm's seed rows that have not finished."""
        return [np.flatnonzero(d < self.setup.episodes).tolist() for d in self.done]

    def record_of(self, job: _Job) -> TaskRecord:
        """A finished job as the run history keeps it."""
        rows = list(job.rows)
        return TaskRecord(
            rows=job.rows, seeds=job.seeds, episodes=job.setup.episodes,
            returns=self.returns[job.arm, rows],
            exact=None if self.exact is None else self.exact[job.arm, rows],
            algorithm=job.algorithm, hyperparameters=job.hp)

    def take(self, index: int, update: SeedsUpdate) -> None:
        """Count in what job `index` played since its last update."""
        job = self.jobs[index]
        for i, row in enumerate(job.rows):
            self.returns[job.arm, row, update.first[i] : update.done[i]] = update.returns[i]
        self.done[job.arm, list(job.rows)] = update.done
        if self.exact is not None and update.exact is not None:
            self.exact[job.arm, list(job.rows)] = update.exact

    def finished(self, job: _Job) -> bool:
        return bool((self.done[job.arm, list(job.rows)] >= job.setup.episodes).all())

    def add(self, jobs: list[_Job]) -> list[_Job]:
        """The jobs, numbered after those there are, and counted in."""
        numbered = [replace(job, index=len(self.jobs) + i) for i, job in enumerate(jobs)]
        self.jobs.extend(numbered)
        self.tasks_total += len(numbered)
        return numbered

    def count(self) -> int:
        return int(self.done.sum())

    def total(self) -> int:
        return len(self.arms) * self.setup.seeds * self.setup.episodes

    def outcomes(self) -> list[AlgorithmOutcome | None]:
        """Each arm's outcome so far (None for one with no episode finished by every seed)."""
        return [self._outcome(a) for a in range(len(self.arms))]

    def _outcome(self, arm: int) -> AlgorithmOutcome | None:
        done, returns, checkpoints = self.done[arm], self.returns[arm], self.checkpoints
        exact = None if self.exact is None else self.exact[arm]
        finished = done >= self.setup.episodes
        if done.min() < 1 and finished.any():  # tasks not begun: the seeds that finished
            done, returns = done[finished], returns[finished]
            exact = None if exact is None else exact[finished]
        common = int(done.min())
        if common < 1:
            return None
        seen = returns[:, :common]
        # The checkpoints' figure: the greedy policy's exact value, or a prediction
        # learner's RMS error of V.
        curve = final = None
        if exact is not None:
            reached = int(np.searchsorted(checkpoints, common, side="right"))
            values = exact[:, :reached]
            finite = np.isfinite(values).all(axis=0)
            keep = np.flatnonzero(finite)
            if keep.size:
                curve = aggregate(values[:, keep], episodes=checkpoints[keep])
            if reached and finite[reached - 1]:
                final = mean_with_ci(values[:, reached - 1])
        mean, ci95 = (None, None) if final is None else (final.mean, final.ci95)
        optimum = self.prepared.optimum
        figures: dict[str, Any] = dict(rms_error=mean, rms_ci95=ci95, rms_curve=curve) if (
            self.predicts[arm]) else dict(exact_value=mean, exact_ci95=ci95, exact_curve=curve,
                                          exact_gap=None if mean is None or optimum is None
                                          else optimum - mean)
        window = max(1, common // SMOOTHING_SHARE)
        return AlgorithmOutcome(
            algorithm=self.arms[arm].algorithm, hyperparameters=self.prepared.hyperparameters[arm],
            seeds_done=int(finished.sum()), curve=aggregate(seen),
            mean_return_last=mean_return_last(seen), run_id=self.run_ids[arm],
            seeds=self.setup.seeds, smoothing=window,
            smoothed=aggregate(seen, window=window) if window > 1 else None, **figures)


class CompareError(RuntimeError):
    """A job of a comparison failed; the message says which and why."""


class ResumeError(CompareError):
    """A run that cannot be resumed with these settings; the message says why."""


def _compared(game: str, algorithm: str, params: Mapping[str, Any],
              wrappers: Sequence[WrapperSetting], seeds: Sequence[int], hp: Mapping[str, Any],
              episodes: int) -> dict[str, Any]:
    """A run's settings as resuming compares them: as JSON reads them back (tuples as lists)."""
    return dict(json.loads(json.dumps({
        "game": game, "algorithm": algorithm, "game parameters": params,
        "wrappers": [w.to_json() for w in wrappers], "seeds": seeds, **dict(sorted(hp.items())),
        "episodes": episodes}, default=str)))


def resumed_group(history: RunHistory, run_id: int, what: str = "") -> list[int]:
    """The ids of the runs run `run_id` heads, its own first; ResumeError (one line) if it
    is not the head of its group (`what`: the group's name, its kind by default)."""
    try:
        head = history.get_run(run_id).summary
        if head.group is not None:
            raise ResumeError(f"run {run_id} is part of run {head.group}'s {what or head.kind}: "
                              f"resume run {head.group}")
        return history.group_ids(run_id)
    except RunHistoryError as exc:
        raise ResumeError(str(exc)) from None


def _resume_runs(
    history: RunHistory, kind: RunKind, setup: Setup, arms: Sequence[Arm], prepared: Prepared,
    resume: int | Sequence[int], tally: _Tally,
) -> list[int | None]:
    """The runs of `resume` (a group's first id, or every id), checked against these settings,
    reopened, their stored tasks counted into `tally`; ResumeError (one line) if they differ."""
    ids = resumed_group(history, resume) if isinstance(resume, int) else resume
    try:
        records = [history.get_run(i) for i in ids]
    except RunHistoryError as exc:
        raise ResumeError(str(exc)) from None
    first = records[0].summary
    if len(records) != len(arms) or any(r.summary.kind != kind for r in records):
        raise ResumeError(f"run {first.id} is a {first.kind} of {len(records)} run(s), not this "
                          f"{kind} of {len(arms)}{RESUME_ADVICE}")
    for a, record in enumerate(records):
        run = record.summary
        tasks = history.read_tasks(run.id)
        here = _compared(prepared.game, arms[a].algorithm, prepared.env_kwargs, prepared.wrappers,
                         setup.seed_list, prepared.hyperparameters[a], setup.episodes)
        there = _compared(run.game, run.algorithm, record.game_params, record.wrappers, run.seeds,
                          record.hyperparameters, tasks[0].episodes if tasks else setup.episodes)
        for key in dict.fromkeys([*here, *there]):
            if there.get(key) != here.get(key):
                raise ResumeError(
                    f"run {run.id} was recorded with other settings ({key} "
                    f"{visible(str(there.get(key)), 60)} there, "
                    f"{visible(str(here.get(key)), 60)} here){RESUME_ADVICE}")
        for task in tasks:
            tally.load(a, task)
    for record in records:
        history.reopen_run(record.summary.id)
    return [r.summary.id for r in records]


def _record(
    history: RunHistory, tally: _Tally, outcomes: Sequence[AlgorithmOutcome | None],
    interrupted: bool,
) -> None:
    status = RunStatus.INTERRUPTED if interrupted else RunStatus.FINISHED
    for run_id, outcome in zip(tally.run_ids, outcomes, strict=True):
        if run_id is None:
            continue
        if outcome is None:
            history.update(run_id, status=status)
            continue
        named = (("return", outcome.curve.downsample(STORED_POINTS)),
                 ("exact_value", outcome.exact_curve), ("rms_error", outcome.rms_curve))
        curves = [c for name, curve in named if curve is not None for c in curve.as_curves(name)]
        history.update(run_id, curves=curves, figures=outcome.figures(), status=status)


@dataclass(frozen=True)
class Executed:
    """What `execute` gives back: each arm's outcome (None if it finished no episode),
    `values[arm, seed, episode]` (NaN where not played) and `exact[arm, seed, checkpoint]`."""

    outcomes: tuple[AlgorithmOutcome | None, ...]
    interrupted: bool
    group: int | None
    prepared: Prepared
    values: np.ndarray
    exact: np.ndarray | None
    tasks: Mapping[str, int] = field(default_factory=dict)  # "done" and "total"


def execute(
    setup: Setup, arms: Sequence[Arm], kind: RunKind, *,
    progress: Callable[[CompareProgress], None] | None = None, stop: threading.Event | None = None,
    history: RunHistory | None = None, processes: int | None = None,
    status: Callable[[str], None] | None = None, resume: int | Sequence[int] | None = None,
    cluster: Any = None, task_seconds: float = TASK_SECONDS, group: int | None = None,
) -> Executed:
    """Train every arm over the setup's seeds as tasks, each kept in the run history as it
    finishes: here when the whole takes under `SPREAD_SECONDS`, else in up to `processes`
    child processes (None: one per core) or on a Dask `cluster` (an address, `local:N`, a
    `distributed.Client`). `resume` (a run's id, or the arms' run ids) runs only the
    tasks its runs miss; `group` is the run the new runs join; `status` hears the engine's
    lines. A task runs for about `task_seconds` or more."""
    from tui_gym.session.experiments.cluster import connect, run_on_cluster

    prepared = prepare(setup, arms)
    with connect(cluster) as client:  # reached (or started) before any run is recorded
        if processes is None:  # the cores this process may run on (where the platform says)
            processes = (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                         else os.cpu_count() or 1)
        cores = max(1, processes)
        tally = _Tally(setup, arms, prepared)
        if resume is not None:
            if history is None:
                raise ResumeError(f"run {resume} cannot be resumed without the run history")
            tally.run_ids = _resume_runs(history, kind, setup, arms, prepared, resume, tally)
        elif history is not None:
            for a, arm in enumerate(arms):  # the first run is the group of those after it
                tally.run_ids[a] = history.start_run(RunSpec(
                    kind=kind, game=prepared.game, algorithm=arm.algorithm,
                    game_params=prepared.env_kwargs, wrappers=prepared.wrappers,
                    hyperparameters=prepared.hyperparameters[a], seeds=setup.seed_list,
                    group=group))
                group = tally.run_ids[a] if group is None else group
        last = [time.monotonic()]

        def tell(force: bool = False) -> None:
            if progress is None:
                return
            now = time.monotonic()
            if force or now - last[0] >= PROGRESS_INTERVAL:
                last[0] = now
                progress(CompareProgress(
                    tally.count(), tally.total(), tally.tasks_done, tally.tasks_total,
                    lambda: tuple(o for o in tally.outcomes() if o is not None)))

        def landed(job: _Job) -> None:
            """A task finished: kept at once, and told."""
            tally.tasks_done += 1
            run_id = tally.run_ids[job.arm]
            if history is not None and run_id is not None:
                history.put_task(run_id, tally.record_of(job))
            tell(force=True)

        halt = threading.Event()
        stopped = halt.is_set if stop is None else (lambda: stop.is_set() or halt.is_set())
        complete = False
        failure: BaseException | None = None
        try:
            with processes_module.stops_on_signals(halt):
                missing = tally.missing()
                seconds = _estimate(prepared, arms, setup, status) if (
                    client is not None or (processes != 0 and cores > 1)) else 0.0
                here = client is None and seconds < SPREAD_SECONDS
                per_seed = seconds / (len(arms) * setup.seeds)
                pieces = 1 if here else max(-(-cores // len(arms)), max(
                    -(-len(rows) * per_seed // task_seconds) for rows in missing))
                jobs = tally.add(_jobs(setup, arms, prepared, missing, int(pieces)))
                if here:
                    complete = _run_here(jobs, tally, stopped, tell, landed)
                elif client is None:
                    complete = _run_children(jobs, tally, stopped, tell, cores, landed)
                else:

                    def take(job: _Job, updates: list[SeedsUpdate]) -> None:
                        for update in updates:
                            tally.take(job.index, update)
                        landed(job)

                    complete = run_on_cluster(client, jobs, run_task, take, stopped)
        except BaseException as exc:
            failure = exc
        if complete and history is not None and None not in tally.run_ids and (
                getattr(history, "failure", None) is None):
            with contextlib.suppress(RunHistoryError):  # a task that does not read: as run
                tally = _stored(history, setup, arms, prepared, tally.run_ids) or tally
        outcomes = tally.outcomes()
        interrupted = not complete
        if history is not None:
            if failure is not None and not isinstance(failure, KeyboardInterrupt):
                for run_id in tally.run_ids:
                    if run_id is not None:
                        history.update(run_id, status=RunStatus.FAILED)
            else:
                _record(history, tally, outcomes, interrupted)
        if failure is not None:
            raise failure
        tell(force=True)
        return Executed(
            outcomes=tuple(outcomes), interrupted=interrupted,
            group=tally.run_ids[0] if tally.run_ids else None, prepared=prepared,
            values=tally.returns, exact=tally.exact,
            tasks={"done": tally.tasks_done, "total": tally.tasks_total},
        )


def _stored(history: RunHistory, setup: Setup, arms: Sequence[Arm], prepared: Prepared,
            run_ids: list[int | None]) -> _Tally | None:
    """The runs' figures as their stored tasks give them (None if some task is missing)."""
    stored = _Tally(setup, arms, prepared)
    stored.run_ids = run_ids
    for a, run_id in enumerate(run_ids):
        assert run_id is not None
        for task in history.read_tasks(run_id):
            stored.load(a, task)
    return stored if not any(stored.missing()) else None


def _estimate(prepared: Prepared, arms: Sequence[Arm], setup: Setup,
              status: Callable[[str], None] | None) -> float:
    """Seconds the whole would take here, from a throwaway learner per arm played for
    `PROBE_SECONDS` (compiling them first, said through `status`); 0 without a model."""
    model = prepared.model
    if model is None:
        return 0.0
    learners = [model.learner(arm.algorithm, prepared.hyperparameters[a], setup.first_seed)
                for a, arm in enumerate(arms)]
    if warm([(x.name, x.arrays(), x.compiled_params()) for x in learners],
            status) and status:
        status("")
    total = 0.0
    checkpoints = len(checkpoint_episodes(setup.episodes))
    for learner in learners:
        # A learner's first call loads its compiled loop (a good part of a second for the
        # first of its kind): paid here, outside the time that is measured.
        play_learner(learner, model.arrays, 1)
        began = time.perf_counter()
        played, _ = play_learner(learner, model.arrays, setup.episodes,
                                 stop=_deadline(began + PROBE_SECONDS / len(learners)))
        rate = len(played) / max(time.perf_counter() - began, 1e-9)
        # Each seed's greedy policy is valued exactly at every checkpoint: on a large
        # model that can cost more than the training.
        table = learner.action_values(slice(None))[None]
        times = []
        for _ in range(2):  # the quicker of two: the first may pay for imports
            began = time.perf_counter()
            model.greedy_values(table)
            times.append(time.perf_counter() - began)
        valuing = checkpoints * min(times)
        total += setup.seeds * (setup.episodes / max(rate, 1e-9) + valuing)
    return total


def _deadline(end: float) -> Callable[[], bool]:
    """A stop flag that is set once the clock passes `end`."""
    return lambda: time.perf_counter() >= end


def run_compare(
    spec: CompareSpec, *, progress: Callable[[CompareProgress], None] | None = None,
    stop: threading.Event | None = None, history: RunHistory | None = None,
    processes: int | None = None, status: Callable[[str], None] | None = None,
    resume: int | None = None, cluster: Any = None,
) -> CompareResult:
    """Run a comparison; the arguments as `execute`'s (`processes` 0: all on this thread).
    ValueError, before anything runs, for an unknown game, algorithm or setting."""
    setup = Setup(spec.game, spec.seeds, spec.episodes, spec.game_params,
                  tuple(spec.wrappers), spec.first_seed)
    arms = [
        Arm(name, {k: v for k, v in spec.settings.items() if _owners(k, [name])}, name)
        for name in spec.algorithms
    ]
    done = execute(setup, arms, RunKind.COMPARE, progress=progress, stop=stop,
                   history=history, processes=processes, status=status, resume=resume,
                   cluster=cluster)
    return CompareResult(
        outcomes=tuple(o for o in done.outcomes if o is not None),
        interrupted=done.interrupted, group=done.group, spec=spec,
        game=done.prepared.game, optimum=done.prepared.optimum, tasks=done.tasks,
    )


def _play(job: _Job, tally: _Tally, stop: Callable[[], bool], tell: Callable[[], None],
          landed: Callable[[_Job], None]) -> bool:
    """Play a job here, counted in and told as it goes; whether it finished (and landed)."""

    def report(update: SeedsUpdate) -> None:
        tally.take(job.index, update)
        tell()

    tally.take(job.index, _run_job(job, stop, report))
    if tally.finished(job):
        landed(job)
    return tally.finished(job)


def _run_here(
    jobs: list[_Job], tally: _Tally, stopped: Callable[[], bool], tell: Callable[[], None],
    landed: Callable[[_Job], None],
) -> bool:
    return all(not stopped() and _play(job, tally, stopped, tell, landed) for job in jobs)


def _run_children(
    jobs: list[_Job], tally: _Tally, stopped: Callable[[], bool], tell: Callable[..., None],
    cores: int, landed: Callable[[_Job], None],
) -> bool:
    # When every job runs at once and this is the main thread (a command, not the app's
    # worker thread), the calling thread plays the last job itself instead of waiting:
    # one process fewer to start, and its results need no passing over.
    alone = 1 < len(jobs) <= cores and threading.current_thread() is threading.main_thread()
    own = jobs[-1] if alone else None
    ctx = processes_module.context()
    messages = ctx.Queue()
    numbers = ctx.Queue()  # the jobs' numbers, then a None for each worker
    stop_flag = ctx.Event()
    given = {job.index: job for job in jobs if job is not own}
    # Long-lived workers, each taking job after job: a process forked per job would copy
    # the tally's pages, which grow with the seeds (a 50,000-run figure's are gigabytes).
    parent = os.getpid()
    width = min(cores, len(given))  # workers at a time

    def hire() -> Any:
        process = ctx.Process(target=_worker, args=(parent, given, numbers, messages,
                                                    stop_flag), daemon=True)
        process.start()
        return process

    workers: list[Any] = []
    left = set(given)  # the workers' jobs not ended yet
    begun: set[int] = set()
    dead_since: dict[int, float] = {}  # workers found ended other than by themselves
    errors: list[str] = []

    def fail(message: str) -> None:
        errors.append(message)
        stop_flag.set()

    def take(timeout: float) -> bool:
        """Take one message (waiting up to `timeout`); False when there was none."""
        if stopped() and not stop_flag.is_set():
            stop_flag.set()
        try:
            kind, index, payload = messages.get(timeout > 0, timeout)  # not blocking for 0
        except queue.Empty:
            return False
        if kind == "begin":
            begun.add(index)
        elif kind == "error":
            fail(str(payload))
        else:
            tally.take(index, payload)
            if kind == "end":
                left.discard(index)
                if tally.finished(tally.jobs[index]):
                    landed(tally.jobs[index])
        return True

    def lost(grace: float) -> None:
        """A worker ended other than by itself: an error, once its last words had `grace` s."""
        now = time.monotonic()
        for w in workers:
            if w.exitcode not in (None, 0) and now - dead_since.setdefault(w.pid, now) >= grace:
                fail(f"a training process ended with code {w.exitcode}")
                return

    finished = False
    try:
        workers.extend(hire() for _ in range(width))
        for index in [*given, *[None] * width]:  # once forked: no feeder thread yet
            numbers.put(index)
        if own is not None:

            def own_stop() -> bool:
                if stopped():
                    stop_flag.set()
                return bool(stop_flag.is_set())

            def own_tell() -> None:
                while take(0):
                    pass
                tell()

            _play(own, tally, own_stop, own_tell, landed)
        while left and not errors:
            took = take(0.05)
            tell()
            if took:
                continue
            if not stop_flag.is_set():
                lost(2.0)
                alive = sum(w.is_alive() for w in workers)
                if len(begun) < len(given) and not errors:  # one that played its share
                    workers.extend(hire() for _ in range(width - alive))
            if not any(w.is_alive() for w in workers):  # stopped, or gone too soon
                while take(0):  # their last words
                    pass
                if left and not errors and not stop_flag.is_set():
                    lost(0.0)
                    if not errors:
                        fail("the training processes ended before their tasks did")
                break
        finished = not errors
    finally:
        stop_flag.set()
        for worker in workers:
            if finished:
                worker.join(timeout=5)
            processes_module.end(worker)
        messages.close()
        numbers.close()
    if errors:
        raise CompareError(errors[0])
    return all(job.index not in left and tally.finished(job) for job in jobs)
