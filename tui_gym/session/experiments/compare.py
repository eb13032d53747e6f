"""Comparisons: several algorithms on one game, each over many seeds, aggregated and recorded.

`run_compare(CompareSpec(...))` trains every (algorithm, seed) from scratch
for the same number of episodes and returns a `CompareResult`: per algorithm,
the per-episode *online* return (what the learner got while exploring)
averaged over seeds with a 95% Student-t band, the mean online return over
the last 10% of episodes with its interval, and, where the game has an exact
model, the greedy policy's exact value at checkpoints and its gap to the
optimum at the end.

Seeds run as batches (`seed_batch.SeedBatch`: one table per seed, all stepped
together); the batches (an algorithm's seeds, `MAX_SEEDS_PER_BATCH` at most in
each) run in child processes, as many at once as there are cores. Called on
the main thread with no more batches than cores, the calling thread plays the
last batch itself while the children play the others.
A game with neither an exact model nor a batched form, or a wrapper without
one, is played seed after seed by the session's scalar engine.

`progress(CompareProgress)` is called on the calling thread about every
`PROGRESS_INTERVAL` seconds with the outcomes so far; setting `stop` (a
`threading.Event`) ends the run at the next step: each algorithm keeps the
episodes all its seeds finished, and the result says `interrupted`. With a
`RunHistory`, each algorithm is recorded as one run of kind `compare` (the
others name the first one as their `group`), with curves `return` and
`exact_value` (each with `.lo` / `.hi`) and figures `mean_return_last`,
`exact_value` and `exact_gap`.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import queue
import signal
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tui_gym.algorithms import ALGORITHMS, algorithm
from tui_gym.core.experiments.aggregate import (
    AggregateCurve,
    Estimate,
    aggregate,
    mean_return_last,
    mean_with_ci,
)
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.history import STORED_POINTS, RunHistory
from tui_gym.core.experiments.records import RunKind, RunSpec, RunStatus, WrapperSetting
from tui_gym.core.experiments.seed_batch import (
    ModelSteps,
    PlanSteps,
    SeedBatch,
    SeedBatchState,
    checkpoint_episodes,
)
from tui_gym.core.mdp import FiniteMDP, model_from_env, solve
from tui_gym.core.wrappers import WrapperChoice

__all__ = [
    "JSON_CURVE_POINTS",
    "AlgorithmOutcome",
    "CompareError",
    "CompareProgress",
    "CompareResult",
    "CompareSpec",
    "run_compare",
]

PROGRESS_INTERVAL = 0.4  # seconds between progress calls
JSON_CURVE_POINTS = 500  # curve points in `to_json`
# Seeds per batch at most. The split depends on the seed count only, never on the cores,
# so a comparison gives the same figures on any machine (a seed's draws depend on its batch).
MAX_SEEDS_PER_BATCH = 64
SMOOTHING_SHARE = 50  # charts smooth each seed's returns over 1/50 of the episodes


@dataclass(frozen=True)
class CompareSpec:
    """What to compare: `algorithms` on `game`, `seeds` seeds each (from `first_seed`),
    `episodes` episodes per seed. `settings` go to every algorithm that has the
    hyperparameter (the budget `episodes` defaults to the comparison's)."""

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
        for name, value in (("seeds", self.seeds), ("episodes", self.episodes)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
        object.__setattr__(self, "algorithms", names)
        object.__setattr__(self, "settings", dict(self.settings))
        object.__setattr__(self, "game_params", dict(self.game_params))
        object.__setattr__(self, "wrappers", tuple(self.wrappers))
        unknown = [k for k in self.settings if not _owners(k, names)]
        if unknown:
            raise ValueError(
                f"no algorithm in the comparison ({', '.join(names)}) has "
                + ", ".join(repr(k) for k in unknown)
                + _known_elsewhere(unknown)
            )

    @property
    def seed_list(self) -> tuple[int, ...]:
        return tuple(range(self.first_seed, self.first_seed + self.seeds))


def _owners(key: str, names: Sequence[str]) -> list[str]:
    return [n for n in names if any(f.name == key for f in algorithm(n).params)]


def _known_elsewhere(keys: Sequence[str]) -> str:
    notes = []
    for key in keys:
        others = [cls.name for cls in ALGORITHMS if any(f.name == key for f in cls.params)]
        if others:
            notes.append(f"{key} belongs to {', '.join(others)}")
    return f" ({'; '.join(notes)})" if notes else ""


@dataclass(frozen=True, eq=False)
class AlgorithmOutcome:
    """One algorithm's results over its seeds (so far, while a comparison runs).

    `curve` is the mean online return per episode with its band, over the
    episodes every seed has finished; `seeds_done` counts the seeds that
    finished all their episodes. `exact_value` / `exact_gap` (None without a
    model) are the mean over seeds of the greedy policy's exact value at the
    last checkpoint every seed reached, and the optimum minus it; `exact_curve`
    is that value at each checkpoint. `run_id` is its run in the history.
    """

    algorithm: str
    hyperparameters: Mapping[str, Any]
    seeds_done: int
    curve: AggregateCurve
    mean_return_last: Estimate
    exact_value: float | None
    exact_gap: float | None
    run_id: int | None
    exact_curve: AggregateCurve | None = None
    exact_ci95: float | None = None
    seeds: int = 0
    smoothed: AggregateCurve | None = None  # each seed's trailing mean over `smoothing` episodes
    smoothing: int = 1

    @property
    def episodes(self) -> int:
        """Episodes every seed has finished."""
        return int(self.curve.episodes[-1]) if len(self.curve) else 0

    def figures(self) -> tuple[Figure, ...]:
        figures = [self.mean_return_last.figure("mean_return_last")]
        if self.exact_value is not None:
            figures.append(Figure("exact_value", self.exact_value, ci95=self.exact_ci95))
        if self.exact_gap is not None:
            figures.append(Figure("exact_gap", self.exact_gap))
        return tuple(figures)

    def to_json(self, max_points: int = JSON_CURVE_POINTS) -> dict[str, Any]:
        return {
            "algorithm": self.algorithm,
            "hyperparameters": dict(self.hyperparameters),
            "seeds_done": self.seeds_done,
            "episodes_done": self.episodes,
            "mean_return_last": _finite(self.mean_return_last.mean),
            "ci95": self.mean_return_last.ci95,
            "exact_value": _finite(self.exact_value),
            "exact_gap": _finite(self.exact_gap),
            "run_id": self.run_id,
            "curve": [p.to_json() for p in self.curve.downsample(max_points).points()],
        }


def _finite(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


@dataclass(frozen=True)
class CompareProgress:
    """Episodes finished of the total (over every algorithm and seed), and the outcomes so far."""

    done: int
    total: int
    outcomes: tuple[AlgorithmOutcome, ...]


@dataclass(frozen=True)
class CompareResult:
    """Every algorithm's outcome; `interrupted` when stopped early; `group` the first run's id."""

    outcomes: tuple[AlgorithmOutcome, ...]
    interrupted: bool
    group: int | None
    spec: CompareSpec | None = None
    game: str = ""
    optimum: float | None = None

    def to_json(self) -> dict[str, Any]:
        spec = self.spec
        return {
            "game": self.game or (spec.game if spec else ""),
            "episodes": spec.episodes if spec else None,
            "seeds": spec.seeds if spec else None,
            "first_seed": spec.first_seed if spec else None,
            "optimum": _finite(self.optimum),
            "interrupted": self.interrupted,
            "group": self.group,
            "results": [o.to_json() for o in self.outcomes],
        }


# --- the plan: what each batch runs ---------------------------------------------------


@dataclass(frozen=True)
class Arm:
    """One learner of an experiment: an algorithm with the settings given for it."""

    algorithm: str
    settings: Mapping[str, Any]
    label: str = ""


@dataclass(frozen=True)
class Setup:
    """What every arm of an experiment shares: the game, its seeds and episodes."""

    game: str
    seeds: int
    episodes: int
    game_params: Mapping[str, Any]
    wrappers: tuple[WrapperChoice, ...]
    first_seed: int

    @property
    def seed_list(self) -> tuple[int, ...]:
        return tuple(range(self.first_seed, self.first_seed + self.seeds))


@dataclass(frozen=True)
class _Job:
    """One batch: an arm's seeds `seeds` (indices `rows` of its seed list)."""

    index: int
    arm: int
    algorithm: str
    env_id: str
    env_kwargs: Mapping[str, Any]
    wrappers: tuple[WrapperChoice, ...]
    hp: Mapping[str, Any]
    seeds: tuple[int, ...]
    rows: tuple[int, ...]
    episodes: int
    model: FiniteMDP | None = None  # the game's exact model, when it has one


@dataclass
class Prepared:
    """The game as built once: its name, id and arguments, each arm's hyperparameters,
    and its exact model and optimum when it has one."""

    game: str
    env_id: str
    env_kwargs: dict[str, Any]
    wrappers: tuple[WrapperSetting, ...]
    hyperparameters: list[dict[str, Any]]
    model: FiniteMDP | None
    optimum: float | None


def _session(
    env_id: str, env_kwargs: Mapping[str, Any], wrappers: Sequence[WrapperChoice], name: str,
    hp: Mapping[str, Any], seed: int,
) -> Any:
    from tui_gym.session.session import Session

    return Session(
        env_id=env_id, env_kwargs=dict(env_kwargs), choices=tuple(wrappers), hp=dict(hp),
        seed=seed, engine="scalar", algorithm=name,
    )


def _game_name(session: Any) -> str:
    game = getattr(session, "game", None) or session.profile
    return str(game.name)


def _exact_model(session: Any) -> FiniteMDP | None:
    """The model of the session's env when its keys are the model's states."""
    keyer = session.keyer
    model = model_from_env(session.env)
    if not isinstance(model, FiniteMDP) or not keyer.dense or keyer.n_states != model.n_states:
        return None
    return model


def prepare(setup: Setup, arms: Sequence[Arm]) -> Prepared:
    """Build the game once per arm: checks every setting, and gives the hyperparameters
    (the budget `episodes` defaults to the experiment's). ValueError for a bad one."""
    hyperparameters: list[dict[str, Any]] = []
    first: Any = None
    for arm in arms:
        values = dict(arm.settings)
        values.setdefault("episodes", setup.episodes)
        session = _session(setup.game, setup.game_params, setup.wrappers, arm.algorithm,
                           values, setup.first_seed)
        hyperparameters.append(dict(session.hp))
        if first is None:
            first = session
        else:
            session.env.close()
    from tui_gym.core.wrappers import get_spec

    wrappers = tuple(
        WrapperSetting(c.name, get_spec(c.name).validate(c.values())) for c in first.applied
    )
    model = _exact_model(first)
    optimum = None
    if model is not None:
        value = solve(model).value
        optimum = value if math.isfinite(value) else None
    prepared = Prepared(
        game=_game_name(first),
        env_id=first.env_id,
        env_kwargs=dict(first.env_kwargs),
        wrappers=wrappers,
        hyperparameters=hyperparameters,
        model=model,
        optimum=optimum,
    )
    first.env.close()
    return prepared


def _cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on every platform
        return max(1, os.cpu_count() or 1)


def _jobs(setup: Setup, arms: Sequence[Arm], prepared: Prepared) -> list[_Job]:
    chunks = math.ceil(setup.seeds / MAX_SEEDS_PER_BATCH)
    bounds = np.linspace(0, setup.seeds, chunks + 1).round().astype(int)
    seeds = setup.seed_list
    jobs: list[_Job] = []
    for a, arm in enumerate(arms):
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            jobs.append(_Job(
                index=len(jobs), arm=a, algorithm=arm.algorithm, env_id=prepared.env_id,
                env_kwargs=prepared.env_kwargs, wrappers=tuple(setup.wrappers),
                hp=prepared.hyperparameters[a], seeds=seeds[lo:hi],
                rows=tuple(range(lo, hi)), episodes=setup.episodes, model=prepared.model,
            ))
    return jobs


# --- running one batch (in a child process or on the calling thread) -------------------


def _run_job(
    job: _Job,
    stop: Callable[[], bool],
    report: Callable[[SeedBatchState], None],
) -> SeedBatchState:
    """Train a job's seeds; its state at the end (complete or stopped)."""
    if job.model is not None:  # the game as its model: no env to build
        learner_class = algorithm(job.algorithm)
        env_seed, learner_seed = _seeds(job)
        batch = SeedBatch(
            learner_class, learner_class.settings(job.hp),
            ModelSteps(job.model, len(job.seeds), env_seed), len(job.seeds), job.episodes,
            seed=learner_seed, model=job.model,
        )
        batch.run(stop=stop, report=lambda b: report(b.state()), interval=PROGRESS_INTERVAL / 2)
        return batch.state()
    session = _session(job.env_id, job.env_kwargs, job.wrappers, job.algorithm, job.hp,
                       job.seeds[0])
    try:
        model = _exact_model(session)
        env_seed, learner_seed = _seeds(job)
        steps: Any = None
        if model is not None:
            steps = ModelSteps(model, len(job.seeds), env_seed)
        else:
            steps = _plan_steps(job, session.keyer, len(job.seeds), env_seed)
        if steps is None:
            return _run_scalar(job, model, stop, report)
        batch = SeedBatch(
            session.learner_class, session.hp, steps, len(job.seeds), job.episodes,
            seed=learner_seed, model=model,
        )
        batch.run(stop=stop, report=lambda b: report(b.state()), interval=PROGRESS_INTERVAL / 2)
        return batch.state()
    finally:
        session.env.close()


def _seeds(job: _Job) -> list[np.random.SeedSequence]:
    """The seeds of a job's envs and of its learner."""
    return np.random.SeedSequence([job.seeds[0], len(job.seeds), job.episodes]).spawn(2)


def _plan_steps(job: _Job, keyer: Any, n: int, seed: Any) -> PlanSteps | None:
    """The vector engine's batched form of the job's game and wrappers, if it has one
    (read from a session on the vector engine, as `train` would build it)."""
    from tui_gym.core.vector import VectorTrainer
    from tui_gym.session.session import Session

    if not keyer.dense:
        return None
    try:
        session = Session(env_id=job.env_id, env_kwargs=dict(job.env_kwargs),
                          choices=tuple(job.wrappers), hp=dict(job.hp), seed=job.seeds[0],
                          engine="vector", algorithm=job.algorithm)
    except ValueError:  # no batched form for this game or these wrappers
        return None
    trainer = session.trainer
    session.env.close()
    if not isinstance(trainer, VectorTrainer):
        return None
    return PlanSteps(trainer.plan, keyer, n, seed)


def _run_scalar(
    job: _Job,
    model: FiniteMDP | None,
    stop: Callable[[], bool],
    report: Callable[[SeedBatchState], None],
) -> SeedBatchState:
    """The seeds one after another on the scalar engine (games with no batched form)."""
    from tui_gym.core.experiments.seed_batch import greedy_values

    n, episodes = len(job.seeds), job.episodes
    checkpoints = checkpoint_episodes(episodes)
    at = {int(c): j for j, c in enumerate(checkpoints)}
    done = np.zeros(n, dtype=np.int64)
    returns = np.full((n, episodes), np.nan)
    exact = None if model is None else np.full((n, len(checkpoints)), np.nan)

    def state() -> SeedBatchState:
        return SeedBatchState(done.copy(), returns[:, : int(done.max())].copy(),
                              checkpoints.copy(), None if exact is None else exact.copy())

    last = time.monotonic()
    for i, seed in enumerate(job.seeds):
        session = _session(job.env_id, job.env_kwargs, job.wrappers, job.algorithm, job.hp,
                           seed)
        try:
            for e in range(episodes):
                if stop():
                    return state()
                returns[i, e] = session.trainer.run_episode().episode_return
                done[i] = e + 1
                j = at.get(e + 1)
                if exact is not None and model is not None and j is not None:
                    q = session.agent.action_values(slice(0, model.n_states))
                    exact[i, j] = greedy_values(model, q[np.newaxis])[0]
                if time.monotonic() - last >= PROGRESS_INTERVAL / 2:
                    report(state())
                    last = time.monotonic()
        finally:
            session.env.close()
    return state()


def _child(job: _Job, messages: Any, stop_flag: Any) -> None:
    """A child process's work: one job, its states sent on `messages`."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides how Ctrl+C ends a run
    try:
        final = _run_job(
            job, stop_flag.is_set, lambda s: messages.put(("state", job.index, s))
        )
    except Exception as exc:  # noqa: BLE001 - sent to the parent, which says it in one line
        messages.put(("error", job.index, f"{type(exc).__name__}: {exc}"))
    else:
        messages.put(("end", job.index, final))


def _context() -> Any:
    """Fork on Linux: the quickest start, and it runs no part of the caller's main module
    again. The children only run batches (no terminal, no locks of the caller's threads),
    so forking from a program with threads (the app) is safe here. Elsewhere, spawn."""
    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("fork")
    return multiprocessing.get_context("spawn")


# --- putting it together ----------------------------------------------------------------


class _Tally:
    """The jobs' latest states, merged per arm."""

    def __init__(
        self, setup: Setup, arms: Sequence[Arm], prepared: Prepared, jobs: list[_Job]
    ) -> None:
        self.setup = setup
        self.arms = arms
        self.prepared = prepared
        self.jobs = jobs
        self.states: dict[int, SeedBatchState] = {}
        self.run_ids: list[int | None] = [None] * len(arms)

    def done(self) -> int:
        return int(sum(int(s.done.sum()) for s in self.states.values()))

    def total(self) -> int:
        return len(self.arms) * self.setup.seeds * self.setup.episodes

    def outcomes(self) -> list[AlgorithmOutcome | None]:
        """Each arm's outcome so far (None for one with no episode finished by every seed)."""
        return [self._outcome(a) for a in range(len(self.arms))]

    def _merged(self, arm: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        setup = self.setup
        checkpoints = checkpoint_episodes(setup.episodes)
        done = np.zeros(setup.seeds, dtype=np.int64)
        returns = np.full((setup.seeds, setup.episodes), np.nan)
        exact = None if self.prepared.model is None else np.full(
            (setup.seeds, len(checkpoints)), np.nan
        )
        for job in self.jobs:
            state = self.states.get(job.index)
            if job.arm != arm or state is None:
                continue
            rows = list(job.rows)
            done[rows] = state.done
            returns[rows, : state.returns.shape[1]] = state.returns
            if exact is not None and state.exact is not None:
                exact[rows] = state.exact
        return done, returns, checkpoints, exact

    def _outcome(self, arm: int) -> AlgorithmOutcome | None:
        done, returns, checkpoints, exact = self._merged(arm)
        common = int(done.min())
        if common < 1:
            return None
        seen = returns[:, :common]
        exact_curve = exact_value = exact_gap = exact_ci = None
        if exact is not None:
            reached = int(np.searchsorted(checkpoints, common, side="right"))
            values = exact[:, :reached]
            finite = np.isfinite(values).all(axis=0)
            keep = np.flatnonzero(finite)
            if keep.size:
                exact_curve = aggregate(values[:, keep], episodes=checkpoints[keep])
            if reached and finite[reached - 1]:
                estimate = mean_with_ci(values[:, reached - 1])
                exact_value, exact_ci = estimate.mean, estimate.ci95
                if self.prepared.optimum is not None:
                    exact_gap = self.prepared.optimum - exact_value
        window = max(1, common // SMOOTHING_SHARE)
        return AlgorithmOutcome(
            algorithm=self.arms[arm].algorithm,
            hyperparameters=self.prepared.hyperparameters[arm],
            seeds_done=int((done >= self.setup.episodes).sum()),
            curve=aggregate(seen),
            mean_return_last=mean_return_last(seen),
            exact_value=exact_value,
            exact_gap=exact_gap,
            run_id=self.run_ids[arm],
            exact_curve=exact_curve,
            exact_ci95=exact_ci,
            seeds=self.setup.seeds,
            smoothed=aggregate(seen, window=window) if window > 1 else None,
            smoothing=window,
        )


def _start_runs(
    history: RunHistory, kind: RunKind, setup: Setup, arms: Sequence[Arm], prepared: Prepared
) -> list[int | None]:
    ids: list[int | None] = []
    group: int | None = None
    for a, arm in enumerate(arms):
        run_id = history.start_run(RunSpec(
            kind=kind,
            game=prepared.game,
            algorithm=arm.algorithm,
            game_params=prepared.env_kwargs,
            wrappers=prepared.wrappers,
            hyperparameters=prepared.hyperparameters[a],
            seeds=setup.seed_list,
            group=group,
        ))
        ids.append(run_id)
        if group is None:
            group = run_id
    return ids


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
        curves = list(outcome.curve.downsample(STORED_POINTS).as_curves("return"))
        if outcome.exact_curve is not None:
            curves.extend(outcome.exact_curve.as_curves("exact_value"))
        history.update(run_id, curves=curves, figures=outcome.figures(), status=status)


@dataclass(frozen=True)
class Executed:
    """What `execute` gives back: each arm's outcome (None if it finished no episode)."""

    outcomes: tuple[AlgorithmOutcome | None, ...]
    interrupted: bool
    group: int | None
    prepared: Prepared


def execute(
    setup: Setup,
    arms: Sequence[Arm],
    kind: RunKind,
    *,
    progress: Callable[[CompareProgress], None] | None = None,
    stop: threading.Event | None = None,
    history: RunHistory | None = None,
    processes: int | None = None,
) -> Executed:
    """Train every arm over the setup's seeds (what `run_compare` and `run_sweep` share)."""
    prepared = prepare(setup, arms)
    cores = _cores() if processes is None else max(1, processes)
    jobs = _jobs(setup, arms, prepared)
    tally = _Tally(setup, arms, prepared, jobs)
    if history is not None:
        tally.run_ids = _start_runs(history, kind, setup, arms, prepared)
    last = [time.monotonic()]

    def tell(force: bool = False) -> None:
        if progress is None:
            return
        now = time.monotonic()
        if force or now - last[0] >= PROGRESS_INTERVAL:
            last[0] = now
            found = tuple(o for o in tally.outcomes() if o is not None)
            progress(CompareProgress(tally.done(), tally.total(), found))

    stopped = stop.is_set if stop is not None else (lambda: False)
    complete = False
    failure: BaseException | None = None
    try:
        if processes == 0:
            complete = _run_here(jobs, tally, stopped, tell)
        else:
            complete = _run_children(jobs, tally, stopped, tell, cores)
    except BaseException as exc:
        failure = exc
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
    )


def run_compare(
    spec: CompareSpec,
    *,
    progress: Callable[[CompareProgress], None] | None = None,
    stop: threading.Event | None = None,
    history: RunHistory | None = None,
    processes: int | None = None,
) -> CompareResult:
    """Run a comparison (see the module docstring).

    `processes`: batches run at once in child processes (None: one per core);
    0 runs them one after another on the calling thread. ValueError, before
    anything runs, for an unknown game, algorithm or setting, or a bad value.
    """
    setup = Setup(spec.game, spec.seeds, spec.episodes, spec.game_params,
                  tuple(spec.wrappers), spec.first_seed)
    arms = [
        Arm(name, {k: v for k, v in spec.settings.items() if _owners(k, [name])}, name)
        for name in spec.algorithms
    ]
    done = execute(setup, arms, RunKind.COMPARE, progress=progress, stop=stop,
                   history=history, processes=processes)
    return CompareResult(
        outcomes=tuple(o for o in done.outcomes if o is not None),
        interrupted=done.interrupted, group=done.group, spec=spec,
        game=done.prepared.game, optimum=done.prepared.optimum,
    )


def _run_here(
    jobs: list[_Job], tally: _Tally, stopped: Callable[[], bool], tell: Callable[..., None]
) -> bool:
    for job in jobs:
        if stopped():
            return False

        def report(state: SeedBatchState, index: int = job.index) -> None:
            tally.states[index] = state
            tell()

        state = _run_job(job, stopped, report)
        tally.states[job.index] = state
        if (state.done < job.episodes).any():
            return False
        tell()
    return True


class CompareError(RuntimeError):
    """A batch of a comparison failed; the message says which and why."""


def _run_children(
    jobs: list[_Job],
    tally: _Tally,
    stopped: Callable[[], bool],
    tell: Callable[..., None],
    cores: int,
) -> bool:
    # When every batch runs at once and this is the main thread (a command, not the app's
    # worker thread), the calling thread plays the last batch itself instead of waiting:
    # one process fewer to start, and its results need no passing over.
    own = None
    if 1 < len(jobs) <= cores and threading.current_thread() is threading.main_thread():
        own = jobs[-1]
    ctx = _context()
    messages = ctx.Queue()
    stop_flag = ctx.Event()
    waiting = [job for job in jobs if job is not own]
    running: dict[int, Any] = {}
    gone: list[Any] = []  # processes that sent their last word, joined at the end
    ended: set[int] = set()
    errors: list[str] = []
    dead_since: dict[int, float] = {}

    def start() -> None:
        if stopped() and not stop_flag.is_set():
            stop_flag.set()
        while waiting and len(running) < cores and not stop_flag.is_set():
            job = waiting.pop(0)
            process = ctx.Process(target=_child, args=(job, messages, stop_flag), daemon=True)
            process.start()
            running[job.index] = process
        if stop_flag.is_set():
            waiting.clear()

    def take(timeout: float) -> bool:
        """Take one message (waiting up to `timeout`); False when there was none."""
        try:
            kind, index, payload = messages.get(timeout=timeout) if timeout else (
                messages.get_nowait()
            )
        except queue.Empty:
            now = time.monotonic()
            for index, process in list(running.items()):
                if process.is_alive():
                    continue
                # Gone without its last word: allow a moment for it to arrive.
                if now - dead_since.setdefault(index, now) > 2.0:
                    running.pop(index)
                    errors.append(f"a batch process ended with code {process.exitcode}")
                    stop_flag.set()
            return False
        message = _take(kind, index, payload, tally, ended, running, gone)
        if message:
            errors.append(message)
            stop_flag.set()
        return True

    try:
        start()
        if own is not None:

            def own_stop() -> bool:
                if stopped():
                    stop_flag.set()
                return bool(stop_flag.is_set())

            def report(state: SeedBatchState) -> None:
                tally.states[own.index] = state
                while take(0):
                    pass
                tell()

            tally.states[own.index] = _run_job(own, own_stop, report)
            ended.add(own.index)
        while waiting or running:
            start()
            take(0.05)
            tell()
    finally:
        stop_flag.set()
        for process in [*running.values(), *gone]:
            process.join(timeout=5)
            if process.is_alive():
                process.terminate()
        messages.close()
    if errors:
        raise CompareError(errors[0])
    return all(
        index in ended and (tally.states[index].done >= job.episodes).all()
        for index, job in enumerate(jobs)
    )


def _take(
    kind: str, index: int, payload: Any, tally: _Tally, ended: set[int],
    running: dict[int, Any], gone: list[Any],
) -> str | None:
    """Take one message from a child; an error's text, if it is one."""
    if kind == "error":
        process = running.pop(index, None)
        if process is not None:
            gone.append(process)
        return str(payload)
    tally.states[index] = payload
    if kind == "end":
        ended.add(index)
        process = running.pop(index, None)
        if process is not None:
            gone.append(process)
    return None
