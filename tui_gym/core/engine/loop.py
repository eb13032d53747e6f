"""The compiled loop over a finite model, the one outcome sampler, and the per-transition entry.

`run_model` keeps the episode in progress between calls, so a run cut into calls of any
size is the same run. Every random number comes from the learner's generator, in one
order: the start, then per transition the action, the outcome, its reward's noise, the
next action (SARSA), and what the rule draws.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any

import numpy as np

from tui_gym.core.engine import jit, processes, rules
from tui_gym.core.engine.kernel import kernel
from tui_gym.core.engine.stats import RollingWindow
from tui_gym.core.mdp.model import FiniteMDP

__all__ = [
    "COLUMNS",
    "FIRST_ACTION",
    "GROW",
    "LENGTH",
    "RETURN",
    "Cursor",
    "ModelArrays",
    "entries",
    "play",
    "run_model",
    "sample_outcome",
    "sample_start",
    "warm",
]

GUIDED = 16  # pairs with more outcomes than this are sampled through a guide table
GROW = 1  # `run_model`'s status when the learner needs room (Monte Carlo's longest episode)

# Columns of `run_model`'s per-episode output (`COLUMNS` of them).
RETURN, LENGTH, MEAN_TD, EPSILON, FIRST_ACTION = range(5)
COLUMNS = 5


@dataclass(frozen=True, eq=False)
class ModelArrays:
    """A model as the loop reads it: flat arrays of K outcomes per row, the starts, the
    table row of each model state, and the episode limit (0: none). Rewards are one row
    per pair; outcomes are row `pair_rows[pair]`, shared by pairs with the same ones
    among many outcomes (more than `GUIDED`) so that draws stay in the cache."""

    next_state: np.ndarray
    cumulative: np.ndarray
    guide: np.ndarray  # [R * K]: per row, where outcome j / K falls (see `sample_outcome`)
    reward: np.ndarray
    noise: np.ndarray  # [S * A * K]: each reward's standard deviation ([0.0]: none has any)
    terminal: np.ndarray
    pair_rows: np.ndarray  # [S * A]
    outcomes: int
    starts: np.ndarray
    start_cumulative: np.ndarray
    rows: np.ndarray
    horizon: int
    n_actions: int

    @classmethod
    def of(cls, model: FiniteMDP, rows: np.ndarray | None = None) -> ModelArrays:
        """The arrays of `model`; `rows[s]` is the table row of model state s (default: s)."""
        starts = np.flatnonzero(model.initial > 0).astype(np.int64)
        start_cumulative = np.cumsum(model.initial[starts])
        start_cumulative[-1] = 1.0
        table_rows = np.arange(model.n_states) if rows is None else np.asarray(rows)
        if table_rows.shape != (model.n_states,):
            raise ValueError(f"rows must have one entry per model state ({model.n_states})")
        outcomes = model.max_outcomes
        cumulative = model.cumulative.reshape(-1, outcomes)
        next_state = model.next_state.reshape(-1, outcomes)
        terminal = model.terminal.reshape(-1, outcomes)
        pair_rows = np.arange(len(cumulative))
        guide = np.zeros(1, dtype=np.int32)
        if outcomes > GUIDED:
            shared: dict[bytes, int] = {}
            for pair in range(len(cumulative)):
                key = (cumulative[pair].tobytes() + next_state[pair].tobytes()
                       + terminal[pair].tobytes())
                pair_rows[pair] = shared.setdefault(key, len(shared))
            first = np.unique(pair_rows, return_index=True)[1]
            cumulative, next_state, terminal = cumulative[first], next_state[first], terminal[first]
            marks = np.arange(outcomes) / outcomes
            guide = np.empty(cumulative.shape, dtype=np.int32)
            for row, values in enumerate(cumulative):
                guide[row] = np.minimum(np.searchsorted(values, marks, side="right"),
                                        outcomes - 1)
        # Writable copies: Numba types a read-only array on its slow path, every call.
        return cls(
            next_state=np.array(next_state.reshape(-1), dtype=np.int64),
            cumulative=np.array(cumulative.reshape(-1), dtype=np.float64),
            guide=guide.reshape(-1),
            reward=np.array(model.reward.reshape(-1), dtype=np.float64),
            noise=(np.zeros(1) if model.reward_std is None or not model.reward_std.any()
                   else np.array(model.reward_std.reshape(-1), dtype=np.float64)),
            terminal=np.array(terminal.reshape(-1), dtype=np.bool_),
            pair_rows=pair_rows.astype(np.int64),
            outcomes=outcomes,
            starts=starts,
            start_cumulative=np.ascontiguousarray(start_cumulative, dtype=np.float64),
            rows=np.array(table_rows, dtype=np.int64),
            horizon=int(model.horizon or 0),
            n_actions=model.n_actions,
        )

    @cached_property
    def args(self) -> tuple[Any, ...]:
        """The fields in `run_model`'s order (all but `n_actions`)."""
        return tuple(getattr(self, f.name) for f in fields(self)[:-1])


class Cursor:
    """An episode in progress between calls of `run_model`."""

    def __init__(self) -> None:
        # live, state, action, steps; this call's episodes and steps; the first action
        self.ints = np.zeros(7, dtype=np.int64)
        self.floats = np.zeros(2, dtype=np.float64)  # return, sum of |TD|

    @property
    def live(self) -> bool:
        return bool(self.ints[0])

    def drop(self) -> None:
        """Abandon the episode in progress (the next call starts a new one)."""
        self.ints[0] = 0


@kernel(inline=True)
def sample_start(starts: Any, start_cumulative: Any, rng: Any) -> int:
    """A start state drawn from the initial distribution (no draw when there is one), by
    bisection (`np.searchsorted` compiles slowly)."""
    n = starts.shape[0]
    if n == 1:
        return starts[0]
    u = rng.random()
    low, high = 0, n
    while low < high:
        middle = low + ((high - low) >> 1)
        if start_cumulative[middle] <= u:
            low = middle + 1
        else:
            high = middle
    return starts[min(low, n - 1)]


@kernel(inline=True)
def sample_outcome(cumulative: Any, guide: Any, base: int, outcomes: int, rng: Any) -> int:
    """Outcome k of the row at `base`, where cumulative[k - 1] <= u < cumulative[k] (no draw
    for one outcome); among many, the search starts where the guide table points."""
    if outcomes == 1:
        return 0
    u = rng.random()
    k = 0
    if outcomes > GUIDED:
        k = guide[base + int(u * outcomes)]
        while k > 0 and u < cumulative[base + k - 1]:
            k -= 1
    while k < outcomes - 1 and u >= cumulative[base + k]:
        k += 1
    return k


@kernel
def run_model(next_state: Any, cumulative: Any, guide: Any, reward: Any, noise: Any,
              terminal: Any, pair_rows: Any, outcomes: int,
              starts: Any, start_cumulative: Any, rows: Any, horizon: int,
              tables: Any, hp: Any, rng: Any, offered: Any, explore: Any, episode0: int,
              cursor: Any, acc: Any, max_episodes: int, max_steps: int,
              out: Any, log: Any) -> int:
    """Play up to `max_episodes` episodes and `max_steps` transitions; `explore` is (epsilon
    start, final, decay episodes). Finished episodes go into `out` rows (`COLUMNS`);
    `cursor[4]`, `cursor[5]` count this call's episodes and steps. Returns 0, or `GROW`."""
    n_actions = tables[0].shape[1]
    values = rules.acting(tables, hp)
    done = 0
    steps = 0
    status = 0
    eps = rules.epsilon_at(float(episode0), explore[0], explore[1], explore[2])
    while done < max_episodes and steps < max_steps:
        if cursor[0] == 0:
            cursor[0] = 1
            cursor[1] = sample_start(starts, start_cumulative, rng)
            cursor[2] = -1
            cursor[3] = 0
            acc[0] = 0.0
            acc[1] = 0.0
            rules.begin(tables, hp)
        if rules.full(tables, hp):
            status = GROW
            break
        s = cursor[1]
        a = cursor[2]
        if a < 0:
            a = rules.act(values, rng, offered, rows[s], eps)
        if cursor[3] == 0:
            cursor[6] = a
        pair = s * n_actions + a
        row = pair_rows[pair] * outcomes
        k = sample_outcome(cumulative, guide, row, outcomes, rng)
        at = pair * outcomes + k
        s2 = next_state[row + k]
        r = reward[at]
        if noise.shape[0] > 1 and noise[at] > 0.0:
            r += noise[at] * rng.standard_normal()
        ended = terminal[row + k]
        cursor[3] += 1
        cut = (not ended) and horizon > 0 and cursor[3] >= horizon
        a2 = -1
        if rules.next_first(hp) and not ended:
            a2 = rules.act(values, rng, offered, rows[s2], eps)
        td = rules.update(tables, hp, rng, offered, rows[s], a, r, rows[s2], ended, cut, a2,
                          eps, log)
        acc[0] += r
        acc[1] += td
        steps += 1
        if ended or cut:
            length = cursor[3]
            out[done, 0] = acc[0]
            out[done, 1] = length
            out[done, 2] = acc[1] / length
            out[done, 3] = eps
            out[done, 4] = cursor[6]
            done += 1
            cursor[0] = 0
            eps = rules.epsilon_at(float(episode0 + done), explore[0], explore[1], explore[2])
        else:
            cursor[1] = s2
            cursor[2] = a2
    cursor[4] = done
    cursor[5] = steps
    return status


# --- called from Python ------------------------------------------------------------------


def play(learner: Any, model: ModelArrays, cursor: Cursor, max_episodes: int,
         max_steps: int, out: np.ndarray, log: np.ndarray) -> tuple[int, int]:
    """One call of `run_model` for `learner`, giving it room when it asks: (episodes, steps)."""
    hp = learner.compiled_params()
    status = entries(hp).run_model(
        *model.args, learner.arrays(), hp, learner.rng, learner.offered_ranges,
        learner.exploration(), learner.episode, cursor.ints, cursor.floats,
        min(max_episodes, len(out)), max_steps, out, log,
    )
    if status == GROW:
        learner.make_room()
    done = int(cursor.ints[4])
    learner.end_episodes(done)
    return done, int(cursor.ints[5])


class Entries:
    """What Python calls for one algorithm: `run_model`, and `transition`, `act` and
    `greedy` through the compiled forms `run_model` calls (nothing more to compile)."""

    def __init__(self, kind: type) -> None:
        self.run_model = jit.entry(run_model, kind)
        self._update = jit.direct(rules.RULES[kind].update)
        own = rules.RULES[kind].acting  # None: every such algorithm acts on one table
        self._act = jit.direct(rules.act, own)
        self._greedy = jit.direct(rules.greedy, own)

    def transition(self, tables: Any, hp: Any, rng: Any, offered: Any, s: int, a: int,
                   r: float, s2: int, terminated: bool, truncated: bool, a2: int,
                   epsilon: float, log: Any) -> tuple[int, float]:
        """The update for one transition played elsewhere, choosing the next action first
        (when `a2` < 0) for a rule that needs it: (that action or -1, |TD|)."""
        if a2 < 0 and rules.next_first(hp) and not terminated:
            a2 = self.act(tables, hp, rng, offered, s2, epsilon)
        td = self._update(tables, hp, rng, offered, s, a, r, s2, terminated, truncated, a2,
                          epsilon, log)
        return a2, float(td)

    def act(self, tables: Any, hp: Any, rng: Any, offered: Any, s: int, epsilon: float) -> int:
        return int(self._act(rules.acting(tables, hp), rng, offered, s, epsilon))

    def greedy(self, tables: Any, hp: Any, rng: Any, offered: Any, s: int) -> int:
        return int(self._greedy(rules.acting(tables, hp), rng, offered, s))


_ENTRIES: dict[type, Entries] = {}


def entries(hp: Any) -> Entries:
    """The entry points for the algorithm whose compiled hyperparameters are `hp`."""
    if type(hp) not in _ENTRIES:
        _ENTRIES[type(hp)] = Entries(type(hp))
    return _ENTRIES[type(hp)]


# --- compiling once ---------------------------------------------------------------------


def compile_learner(tables: Any, hp: Any) -> None:
    """Compile (or load) the entry points for one learner's types, on copies of its tables
    and a model of one state where every action ends the episode."""
    calls = entries(hp)
    copies = tuple(np.array(t) for t in tables)
    mask = rules.offered_ranges(None, copies[0].shape[1])
    spare = np.random.default_rng(0)
    log = np.zeros((1, 8))
    shape = (1, copies[0].shape[1], 1)
    model = ModelArrays.of(FiniteMDP(np.zeros(shape, dtype=np.int64), np.ones(shape),
                                     np.zeros(shape), np.ones(shape, dtype=bool), np.ones(1)))
    cursor = Cursor()
    calls.run_model(*model.args, copies, hp, spare, mask, np.zeros(3), 0, cursor.ints,
                    cursor.floats, 1, 1, np.zeros((1, COLUMNS)), log)
    calls.transition(copies, hp, spare, mask, 0, 0, 0.0, 0, True, False, -1, 0.0, log)
    calls.act(copies, hp, spare, mask, 0, 0.0)
    calls.greedy(copies, hp, spare, mask, 0)
    RollingWindow(1).push_many(np.zeros(1))  # the trainer's statistics of each call


def warm(learners: Sequence[tuple[str, Any, Any]],
         progress: Callable[[str], None] | None = None) -> bool:
    """Compile (or load) each `(name, tables, hp)` learner's entry points, telling `progress`
    of those not compiled before: the first here, the others in worker processes
    (`compile_apart`). True when anything had to be compiled."""
    wanted = {learner[0]: learner for learner in learners}
    if all(key in _WARM for key in wanted):
        return False
    folder = jit.folder()
    cold = [(k, x) for k, x in wanted.items() if not (folder / f"warm-{k}").exists()]
    apart = [False] * len(cold)
    finished = iter(range(2, len(cold) + 1))

    def say(name: str, index: int) -> None:
        if progress is not None:
            progress(f"{jit.COMPILING} ({index}/{len(cold)}: {name})")

    for index, (key, (name, tables, hp)) in enumerate(cold, start=1):
        if index == 2:  # what every learner shares is compiled: the workers inherit it
            apart[1:] = compile_apart([x for _, x in cold[1:]],
                                      lambda name: say(name, next(finished)))
        if not apart[index - 1]:
            say(name, index)
        compile_learner(tables, hp)
        with contextlib.suppress(OSError):  # a read-only cache works, only looked at again
            (folder / f"warm-{key}").write_text("ok\n")
    _WARM.update(wanted)
    return bool(cold)


def compile_apart(learners: Sequence[tuple[str, Any, Any]],
                  done_with: Callable[[str], None] | None = None) -> list[bool]:
    """Compile each `(name, tables, hp)` learner's entry points into the cache in worker
    processes, one per core, telling `done_with` each name as done. Per learner, whether
    it was (False where workers cannot start: the caller compiles them)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    workers = min(len(learners), cores or 1)
    done = [False] * len(learners)
    if workers < 2 or not jit.compiles():
        return done
    pool = ProcessPoolExecutor(workers, mp_context=processes.context(),
                               initializer=processes.watch_parent, initargs=(os.getpid(),))
    try:
        futures = {pool.submit(compile_learner, *learner[1:]): i
                   for i, learner in enumerate(learners)}
        for future in as_completed(futures):
            index = futures[future]
            done[index] = future.exception() is None
            if done_with is not None:
                done_with(learners[index][0])
    except (OSError, RuntimeError):  # workers that cannot start or died: the caller compiles
        pass
    finally:
        pool.shutdown(wait=False, cancel_futures=True)  # at once, on Ctrl+C too
    return done


_WARM: set[str] = set()  # learners whose entry points this process has made ready
