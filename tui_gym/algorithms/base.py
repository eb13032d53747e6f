"""The learner protocol: what every tabular algorithm provides and how engines drive it.

A learner is one subclass of `Learner` that declares its name, its
hyperparameter schema (`params`), the per-(state, action) tables it keeps
(`tables`), and writes two methods: `update(batch)`, its rule, batched, and
`_describe`, the record of a batch of one (built only when asked for, from
figures `update` kept). The base class owns everything else: the rows of
the tables (dense observation keys are rows; other keys get the next free
row, and the tables grow), epsilon-greedy acting, the epsilon schedule,
reading values for heatmaps and evaluation, and saving (`state()` /
`load_state()`).

How an engine drives a learner, each step of a batch of envs:

1. Actions: `act_batch(rows)` for every stepping env, from the table as the
   last update left it; but for a learner with `needs_next_action` (SARSA)
   the actions chosen in step 3 of the previous step, and `act_batch` only
   for episodes that just started.
2. Step the envs; table rows of the next observations (`rows(keys)`; dense
   keys are rows).
3. With `needs_next_action`: every row's next action now, `act_batch(next
   rows)`, before the update; the engine then takes exactly these (for
   ended episodes they are only read, to bootstrap after a truncation).
4. `update(Transitions(...))`: the rule, once per step; a TD error per row
   (for the mean |TD| statistic).
5. `end_episodes(count)` for the episodes that ended: epsilon moves on.
6. `forget_episodes(envs)` for episodes abandoned before their end (the
   engine rebuilt or reset mid-way).

The scalar engine is the same with one env, through `act(key)` and
`update_one(key, ...)`: they draw from the generator and round as the
one-at-a-time agent always did (`Transitions.one` is `sequential`), while
`act_batch` and `update` do as the batched trainer did, so Q-learning gives
each engine's old numbers. `last_update` explains a batch of one for the
step-by-step view.

`Transitions.env` names the episode each row belongs to, so Monte Carlo can
keep one trajectory per env: ids are non-negative and distinct among all
episodes in progress on the learner; engines that share one learner use
disjoint ids (the scalar engine `SCALAR_ENV`, a vector engine `1 + index`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Hashable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from tui_gym.algorithms.exploration import (
    epsilon_greedy_batch,
    epsilon_greedy_one,
    greedy_batch,
    greedy_one,
)
from tui_gym.algorithms.settings import COMMON_PARAMS, Field, Settings
from tui_gym.algorithms.steps import move_toward, step_size

__all__ = [
    "SCALAR_ENV",
    "CellUpdate",
    "Learner",
    "LearnerState",
    "TableSpec",
    "Transitions",
    "UpdateRecord",
]

SCALAR_ENV = 0
"""The env id the scalar engine gives its one episode stream."""

# Rows a growing (sparse) table starts with; it doubles when full.
_INITIAL_ROWS = 256
# The largest count a saved table may hold (far beyond any run; keeps sums in int64).
MAX_SAVED_COUNT = 2**62


@dataclass(frozen=True)
class Transitions:
    """A batch of B transitions, row i from env `env[i]`.

    `state`, `next_state`: table rows (`Learner.rows`); `next_state` is the
    observation after the action, for an ended episode its final one (the
    one to bootstrap from after a truncation). `next_action`: the action
    the engine will take in `next_state` (learners with `needs_next_action`).
    `terminated` ends the bootstrap; `truncated` ends the episode but the
    value of `next_state` still counts. `env`: None for `arange(B)`.
    `sequential` marks one transition of a one-at-a-time stream (the scalar
    engine, `Transitions.one`): its update is the textbook `Q + α(t - Q)`,
    where batches use a closed form that agrees up to rounding. Each engine
    thus keeps the exact numbers of its one-rule-per-engine predecessor.
    """

    state: np.ndarray  # int64 (B,)
    action: np.ndarray  # int64 (B,)
    reward: np.ndarray  # float64 (B,)
    next_state: np.ndarray  # int64 (B,)
    terminated: np.ndarray  # bool (B,)
    truncated: np.ndarray  # bool (B,)
    next_action: np.ndarray | None = None  # int64 (B,)
    env: np.ndarray | None = None  # int64 (B,), distinct
    sequential: bool = False

    def __len__(self) -> int:
        return len(self.state)

    @classmethod
    def one(
        cls,
        state: int,
        action: int,
        reward: float,
        next_state: int,
        terminated: bool,
        truncated: bool = False,
        next_action: int | None = None,
        env: int = SCALAR_ENV,
    ) -> Transitions:
        """A batch of one transition."""
        return cls(
            np.array([state], dtype=np.int64),
            np.array([action], dtype=np.int64),
            np.array([reward], dtype=np.float64),
            np.array([next_state], dtype=np.int64),
            np.array([terminated], dtype=bool),
            np.array([truncated], dtype=bool),
            None if next_action is None else np.array([next_action], dtype=np.int64),
            np.array([env], dtype=np.int64),
            sequential=True,
        )

    def envs(self) -> np.ndarray:
        return np.arange(len(self.state)) if self.env is None else self.env


@dataclass(frozen=True)
class CellUpdate:
    """One (state, action) moved toward a target: a row of an update's explanation."""

    state: int
    action: int
    target: float
    step_size: float
    before: float
    after: float

    @property
    def td_error(self) -> float:
        return self.target - self.before


@dataclass(frozen=True)
class UpdateRecord:
    """How a learner used one transition: what the step-by-step view shows.

    `formula` is the target as the algorithm forms it (`r + γ·max Q(s',·)`),
    `terms` each symbol of it with its value, in order. `target`, `td_error`
    and `step_size` are None when the transition updates nothing yet (Monte
    Carlo before the episode's end). `before`/`after` are Q(s, a) of the
    table that was updated (`table` names it when there are two).
    `target_action`: the action in s' whose value the target reads (SARSA's
    a', Double Q's argmax of the updated table), None for a max or an
    expectation.
    `episode_updates`: Monte Carlo's updates at the episode's end, each with
    its return; `planning_updates`: Dyna-Q's simulated updates after the
    real one (`after` is Q(s, a) before planning).
    """

    algorithm: str
    state: int
    action: int
    reward: float
    next_state: int
    next_action: int | None
    terminated: bool
    truncated: bool
    formula: str
    terms: tuple[tuple[str, float], ...]
    target: float | None
    td_error: float | None
    step_size: float | None
    before: float
    after: float
    table: str = ""
    target_action: int | None = None
    episode_return: float | None = None
    episode_updates: tuple[CellUpdate, ...] = ()
    planning_updates: int = 0


@dataclass(frozen=True)
class TableSpec:
    """One per-(state, action) table a learner keeps: its name, dtype and initial value."""

    name: str
    dtype: type
    fill: float | int | bool = 0


@dataclass(frozen=True)
class LearnerState:
    """Everything a learner saves: named arrays, JSON-able metadata, and sparse row keys.

    `arrays` hold every table's used rows and any other learner arrays;
    `meta` has the algorithm name, table shape, episode count and
    hyperparameters; `keys` is the key of each row for sparse tables, None
    when rows are dense keys.
    """

    algorithm: str
    arrays: dict[str, np.ndarray]
    meta: dict[str, Any]
    keys: list[Hashable] | None = None


class Learner(ABC):
    """A tabular learner over `n_actions` actions (see the module docstring for the protocol).

    `n_states` fixes a dense table (keys are rows); None grows the table as
    new keys come. `hyperparameters` is a mapping of values for `params`
    (missing ones take their defaults) or `Settings`. `seed` seeds the one
    generator behind acting and any randomness in the rule.
    """

    name: ClassVar[str]  # the registry name: `--algorithm NAME`, save files
    title: ClassVar[str]  # how a person reads it
    summary: ClassVar[str]  # one line: what it teaches
    formula: ClassVar[str]  # its target, as the step-by-step view writes it
    params: ClassVar[tuple[Field, ...]] = COMMON_PARAMS
    tables: ClassVar[tuple[TableSpec, ...]] = (
        TableSpec("q", np.float64),
        TableSpec("counts", np.int64),
    )
    needs_next_action: ClassVar[bool] = False
    # The tables named in `tables` (these two for most learners) are attributes.
    q: np.ndarray
    counts: np.ndarray

    def __init__(
        self,
        n_actions: int,
        hyperparameters: Mapping[str, Any] | None = None,
        *,
        n_states: int | None = None,
        seed: int | None = None,
    ) -> None:
        if n_actions < 1:
            raise ValueError(f"n_actions must be >= 1, got {n_actions}")
        if n_states is not None and n_states < 1:
            raise ValueError(f"n_states must be >= 1, got {n_states}")
        self.n_actions = int(n_actions)
        self.n_states = None if n_states is None else int(n_states)
        self.hp = self.settings(hyperparameters)
        self.rng = np.random.default_rng(seed)
        self.episode = 0  # episodes finished; drives the epsilon schedule
        self.epsilon = self.hp.epsilon_at(0)
        self._last: tuple[Transitions, tuple[Any, ...]] | None = None  # see `last_update`
        self._last_record: UpdateRecord | None = None
        self._index: dict[Hashable, int] | None = None if n_states is not None else {}
        capacity = self.n_states if self.n_states is not None else _INITIAL_ROWS
        self._rows_used = self.n_states if self.n_states is not None else 0
        self.visits = np.zeros(capacity, dtype=np.int64)  # updates per state
        for spec in self.tables:
            setattr(self, spec.name, np.full((capacity, self.n_actions), spec.fill, spec.dtype))

    @classmethod
    def settings(cls, values: Mapping[str, Any] | None = None) -> Settings:
        """Validated hyperparameters for this algorithm (defaults for what is missing)."""
        if isinstance(values, Settings) and values.schema == cls.params:
            return values
        return Settings(cls.params, values)

    @classmethod
    def hyperparameters(cls, **values: Any) -> Settings:
        """Settings for this algorithm from keyword values (defaults for the rest)."""
        return cls.settings(values)

    # --- the rule: what a subclass writes --------------------------------------
    @abstractmethod
    def update(self, batch: Transitions) -> np.ndarray:
        """Learn from a batch of transitions; one TD error per row.

        A batch of one also leaves `last_update`, a record of the update.
        """

    def action_values(self, rows: np.ndarray | slice) -> np.ndarray:
        """The values the policy acts on, per row (k, n_actions)."""
        return self.q[rows]

    def forget_episodes(self, envs: Sequence[int] | np.ndarray | None = None) -> None:
        """Drop what is kept of unfinished episodes (all envs when None)."""
        return None  # only learners that keep episodes (Monte Carlo) have any

    def _extra_arrays(self) -> dict[str, np.ndarray]:
        """Arrays to save beyond the tables (copies)."""
        return {}

    def _load_extra_arrays(self, arrays: Mapping[str, np.ndarray], rows: int) -> None:
        """Take back what `_extra_arrays` saved; raise ValueError before changing anything."""
        return None

    def _check_arrays(self, arrays: Mapping[str, np.ndarray], rows: int) -> None:
        """Raise ValueError, naming the array, for saved values this learner could not
        have made: another kind of number, NaN or infinite values, counts below the
        table's fill or beyond `MAX_SAVED_COUNT`. Shapes are checked before."""
        specs = (TableSpec("visits", np.int64), *self.tables)
        for spec in specs:
            array = np.asarray(arrays[spec.name])
            kind = array.dtype.kind
            if spec.dtype is bool:
                if kind != "b":
                    raise ValueError(f"saved {spec.name!r} holds {array.dtype} values, not bool")
            elif np.issubdtype(spec.dtype, np.floating):
                if kind not in "fiu":
                    raise ValueError(f"saved {spec.name!r} holds {array.dtype} values")
                if not np.isfinite(array).all():
                    raise ValueError(f"saved {spec.name!r} holds NaN or infinite values")
            else:
                if kind not in "iu":
                    raise ValueError(f"saved {spec.name!r} holds {array.dtype} values")
                low = min(0, int(spec.fill))
                if array.size and (array.min() < low or array.max() > MAX_SAVED_COUNT):
                    raise ValueError(f"saved {spec.name!r} holds negative or impossible counts")

    def _move(
        self,
        table: np.ndarray,
        counts: np.ndarray,
        cells: np.ndarray,
        targets: np.ndarray,
        sequential: bool,
        *,
        count: bool = True,
    ) -> np.ndarray:
        """`move_toward` with this learner's step sizes and visit counts; the TD errors."""
        hp = self.hp
        return move_toward(
            table, counts, self.visits, cells, targets, hp.learning_rate,
            hp.learning_rate_schedule, count=count, sequential=sequential,
        )

    def _move_q(
        self, batch: Transitions, targets: np.ndarray, future: np.ndarray, *extra: Any
    ) -> np.ndarray:
        """Move `q` at the batch's (state, action) cells toward `targets`; the TD errors.
        A batch of one keeps its figures for `_describe`: target, future, Q before and
        after, the cell's count, then `extra`."""
        cells = batch.state * self.n_actions + batch.action
        q_flat = self.q.reshape(-1)
        before = q_flat[cells[0]] if len(cells) == 1 else None
        td = self._move(self.q, self.counts, cells, targets, batch.sequential)
        if before is None:
            self._last = None
        else:
            self._keep(batch, targets[0], future[0], before, q_flat[cells[0]],
                       self.counts.reshape(-1)[cells[0]], *extra)
        return td

    # --- rows ----------------------------------------------------------------------
    @property
    def dense(self) -> bool:
        return self._index is None

    @property
    def rows_used(self) -> int:
        return self._rows_used

    def row(self, key: Hashable) -> int:
        """The table row of a key, adding one for a new sparse key."""
        index = self._index
        if index is None:
            return key  # type: ignore[return-value]
        row = index.get(key)
        if row is None:
            row = self._rows_used
            if row == len(self.visits):
                self._grow()
            index[key] = row
            self._rows_used += 1
        return row

    def rows(self, keys: Iterable[Hashable]) -> np.ndarray:
        """The rows of many keys (adding new sparse keys), as an int64 array."""
        if self._index is None:
            return np.asarray(keys if isinstance(keys, np.ndarray) else list(keys), dtype=np.int64)
        return np.fromiter((self.row(k) for k in keys), dtype=np.int64)

    def find(self, key: Hashable) -> int | None:
        """The row of a key, or None when a sparse table has never seen it."""
        if self._index is None:
            return key  # type: ignore[return-value]
        return self._index.get(key)

    def _grow(self) -> None:
        def doubled(array: np.ndarray) -> np.ndarray:
            return np.concatenate([array, np.zeros_like(array)])

        self.visits = doubled(self.visits)
        for spec in self.tables:
            old = getattr(self, spec.name)
            setattr(self, spec.name, np.concatenate([old, np.full_like(old, spec.fill)]))

    def _row_values(self, key: Hashable) -> np.ndarray:
        row = self.find(key)
        if row is None:  # an unseen state reads as all zeros, as an untouched row does
            return np.zeros(self.n_actions)
        return self.action_values(np.array([row]))[0]

    # --- acting ----------------------------------------------------------------------
    def act(self, key: Hashable) -> int:
        """Epsilon-greedy for one state (the scalar engine's draw order)."""
        return epsilon_greedy_one(self._row_values(key), self.epsilon, self.rng)

    def act_batch(self, rows: np.ndarray) -> np.ndarray:
        """Epsilon-greedy for many rows (the vector engine's draw order)."""
        return epsilon_greedy_batch(self.action_values(rows), self.epsilon, self.rng)

    def greedy(self, key: Hashable) -> int:
        """The best-valued action in a state, ties broken at random."""
        return greedy_one(self._row_values(key), self.rng)

    def greedy_batch(self, rows: np.ndarray) -> np.ndarray:
        return greedy_batch(self.action_values(rows), self.rng)

    def greedy_actions(self, key: Hashable) -> tuple[int, ...]:
        """Every action tied for the best value in a state."""
        values = self._row_values(key)
        return tuple(int(a) for a in np.flatnonzero(values == values.max()))

    # --- the schedule ------------------------------------------------------------------
    def end_episodes(self, count: int = 1) -> None:
        """Count finished episodes and move epsilon along its schedule."""
        self.episode += count
        self.epsilon = self.hp.epsilon_at(self.episode)

    def end_episode(self) -> None:
        self.end_episodes(1)

    def set_hyperparameters(self, hyperparameters: Mapping[str, Any]) -> None:
        """New values for the rest of the run, taking effect at once; tables and episodes stay."""
        self.hp = self.settings(hyperparameters)
        self.epsilon = self.hp.epsilon_at(self.episode)

    # --- the scalar engine's convenience -------------------------------------------------
    def update_one(
        self,
        key: Hashable,
        action: int,
        reward: float,
        next_key: Hashable,
        terminated: bool,
        truncated: bool = False,
        next_action: int | None = None,
        env: int = SCALAR_ENV,
    ) -> float:
        """One transition by observation keys, as a batch of one; its TD error."""
        state = self.row(key)
        batch = Transitions.one(
            state, action, reward, self.row(next_key), terminated, truncated, next_action, env
        )
        return float(self.update(batch)[0])

    # --- reading the table ----------------------------------------------------------------
    def values(self, keys: Iterable[Hashable]) -> np.ndarray:
        """Action values for many states: (len(keys), n_actions); unseen states are 0."""
        keys = list(keys)
        out = np.zeros((len(keys), self.n_actions), dtype=np.float64)
        if self._index is None:
            if keys:
                out[:] = self.action_values(np.asarray(keys, dtype=np.int64))
            return out
        found = [(i, self._index.get(k)) for i, k in enumerate(keys)]
        found = [(i, r) for i, r in found if r is not None]
        if found:
            at, rows = zip(*found, strict=True)
            out[list(at)] = self.action_values(np.asarray(rows, dtype=np.int64))
        return out

    def table(self) -> tuple[np.ndarray, list[Hashable] | None]:
        """The action values of the used rows and, for sparse tables, each row's key."""
        values = self.action_values(slice(0, self._rows_used))
        return values.copy(), self._keys()

    def _keys(self) -> list[Hashable] | None:
        if self._index is None:
            return None
        keys: list[Hashable] = [None] * self._rows_used
        for key, row in self._index.items():
            keys[row] = key
        return keys

    def update_counts(self) -> np.ndarray:
        """Updates per (state, action) of the used rows."""
        return self.counts[: self._rows_used].copy()

    def seen(self, key: Hashable) -> bool:
        """Whether the learner has updated this state at least once."""
        row = self.find(key)
        return row is not None and bool(self.visits[row])

    @property
    def states_seen(self) -> int:
        """How many states have been updated at least once."""
        return int(np.count_nonzero(self.visits[: self._rows_used]))

    # --- the record of a batch of one ---------------------------------------------------
    @property
    def last_update(self) -> UpdateRecord | None:
        """How the latest update used its transition, when that update was a batch of one."""
        if self._last is None:
            return None
        if self._last_record is None:
            batch, numbers = self._last
            self._last_record = self._describe(batch, *numbers)
        return self._last_record

    def _keep(self, batch: Transitions, *numbers: Any) -> None:
        """Keep a batch of one's figures (plain numbers read now); the record is built on demand."""
        self._last = (batch, numbers)
        self._last_record = None

    @abstractmethod
    def _describe(self, batch: Transitions, *numbers: Any) -> UpdateRecord:
        """The record of a batch of one from the figures `update` kept with `_keep`."""

    def _record(
        self,
        batch: Transitions,
        formula: str,
        terms: tuple[tuple[str, float], ...],
        target: float | None,
        before: float,
        after: float,
        n: int = 0,
        alpha: float | None = None,
        **extra: Any,
    ) -> UpdateRecord:
        """An `UpdateRecord` for a batch of one.

        The step size is `alpha`, or else the schedule's for the cell's n-th
        update (`n` counting this one).
        """
        if target is not None and alpha is None:
            alpha = step_size(self.hp.learning_rate, self.hp.learning_rate_schedule, max(n, 1))
        return UpdateRecord(
            algorithm=self.name,
            state=int(batch.state[0]),
            action=int(batch.action[0]),
            reward=float(batch.reward[0]),
            next_state=int(batch.next_state[0]),
            next_action=None if batch.next_action is None else int(batch.next_action[0]),
            terminated=bool(batch.terminated[0]),
            truncated=bool(batch.truncated[0]),
            formula=formula,
            terms=terms,
            target=None if target is None else float(target),
            td_error=None if target is None else float(target) - float(before),
            step_size=alpha,
            before=float(before),
            after=float(after),
            **extra,
        )

    # --- saving ------------------------------------------------------------------------------
    def state(self) -> LearnerState:
        """Copies of everything that defines this learner, to save or send elsewhere."""
        used = self._rows_used
        arrays = {"visits": self.visits[:used].copy()}
        for spec in self.tables:
            arrays[spec.name] = getattr(self, spec.name)[:used].copy()
        arrays.update(self._extra_arrays())
        meta = {
            "algorithm": self.name,
            "n_actions": self.n_actions,
            "n_states": self.n_states,
            "rows": used,
            "episode": self.episode,
            "hyperparameters": self.hp.to_dict(),
        }
        return LearnerState(self.name, arrays, meta, self._keys())

    def load_state(self, state: LearnerState) -> None:
        """Become the learner `state` describes (the generator is kept).

        Raises ValueError, changing nothing, when it is another algorithm's or
        does not fit this learner's shape.
        """
        if state.algorithm != self.name:
            raise ValueError(f"this is a {state.algorithm} learner's state, not {self.name}'s")
        meta, arrays = state.meta, state.arrays
        rows = int(meta.get("rows", -1))
        if int(meta.get("n_actions", -1)) != self.n_actions:
            raise ValueError(
                f"the saved table has {meta.get('n_actions')} actions, this one {self.n_actions}"
            )
        dense = state.keys is None
        if dense != self.dense:
            raise ValueError(
                "the saved table is dense, this one sparse" if dense
                else "the saved table is sparse, this one dense"
            )
        if dense and rows != self.n_states:
            raise ValueError(f"the saved table has {rows} states, this one {self.n_states}")
        if not dense and len(state.keys) != rows:  # type: ignore[arg-type]
            raise ValueError("sparse table keys and rows differ in number")
        hp = self.settings(meta.get("hyperparameters"))
        shapes = {"visits": (rows,)} | {s.name: (rows, self.n_actions) for s in self.tables}
        for name, shape in shapes.items():
            if name not in arrays:
                raise ValueError(f"the saved state has no {name!r} array")
            if np.shape(arrays[name]) != shape:
                raise ValueError(
                    f"saved {name!r} has shape {np.shape(arrays[name])}, expected {shape}"
                )
        self._check_arrays(arrays, rows)
        capacity = rows if dense else max(_INITIAL_ROWS, rows)
        loaded: dict[str, np.ndarray] = {}
        for spec in self.tables:
            filled: np.ndarray = np.full((capacity, self.n_actions), spec.fill, spec.dtype)
            filled[:rows] = arrays[spec.name]
            loaded[spec.name] = filled
        visits = np.zeros(capacity, dtype=np.int64)
        visits[:rows] = arrays["visits"]
        self._load_extra_arrays(arrays, rows)
        for name, table in loaded.items():
            setattr(self, name, table)
        self.visits = visits
        self._rows_used = rows
        self._index = None if dense else {k: i for i, k in enumerate(state.keys)}  # type: ignore[arg-type]
        self.hp = hp
        self.episode = int(meta.get("episode", 0))
        self.epsilon = hp.epsilon_at(self.episode)
        self._last = self._last_record = None
        self.forget_episodes()

    @classmethod
    def from_state(cls, state: LearnerState, seed: int | None = None) -> Learner:
        """A new learner of this class restored from `state`."""
        meta = state.meta
        learner = cls(
            int(meta["n_actions"]),
            meta.get("hyperparameters"),
            n_states=None if state.keys is not None else int(meta["rows"]),
            seed=seed,
        )
        learner.load_state(state)
        return learner

    def assign_from(self, other: Learner) -> None:
        """Become a copy of `other` (tables, schedule, generator), keeping identity."""
        if other is self:
            return
        if type(other) is not type(self):
            raise ValueError(f"cannot take over a {other.name} learner as {self.name}")
        if other.n_actions != self.n_actions or other.n_states != self.n_states:
            raise ValueError("cannot take over a learner of a different shape")
        vars(self).update(vars(other))

    def __repr__(self) -> str:
        shape = f"{self.n_states} states" if self.n_states is not None else "sparse"
        return f"{type(self).__name__}({shape}, {self.n_actions} actions, episode {self.episode})"
