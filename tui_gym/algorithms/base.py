"""The learner: what a tabular algorithm declares, and what the engine drives."""

from __future__ import annotations

import keyword
from abc import ABC, abstractmethod
from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from tui_gym.algorithms.settings import COMMON_PARAMS, Field, Settings
from tui_gym.core.engine import loop, rules
from tui_gym.core.engine.kernel import kernel

__all__ = ["CellUpdate", "Extra", "Learner", "LearnerState", "TableSpec", "Transition",
           "UpdateRecord", "filled", "note", "restart"]


@kernel(inline=True)
def note(log: Any, row: int, c0: float, c1: float, c2: float, c3: float, c4: float,
         c5: float) -> None:
    """Row `row` of an update's log, when it has one, gets six numbers from column 0."""
    if row < log.shape[0]:
        log[row, 0] = c0
        log[row, 1] = c1
        log[row, 2] = c2
        log[row, 3] = c3
        log[row, 4] = c4
        log[row, 5] = c5


# Rows a growing (sparse) table starts with; it doubles when full.
_INITIAL_ROWS = 256
_FIRST_STEPS = 64  # steps of an episode an "episode" extra holds before it doubles
# The largest count a saved table may hold (far beyond any run; keeps sums in int64).
MAX_SAVED_COUNT = 2**62


@kernel(inline=True)
def restart(tables: Any, hp: Any) -> None:
    """`begin` of a rule that keeps the episode so far: its length (the last array) to 0."""
    tables[-1][0] = 0


@kernel(inline=True)
def filled(tables: Any, hp: Any) -> bool:
    """`full` of a rule that keeps the episode so far (arrays 4 on, its length last)."""
    return tables[-1][0] >= tables[4].shape[0]


@dataclass(frozen=True)
class CellUpdate:
    """One (state, action) moved toward a target: a row of an update's explanation
    (`trace`: its eligibility, for a learner that moves pairs by their traces)."""

    state: int
    action: int
    target: float
    step_size: float
    before: float
    after: float
    trace: float | None = None

    @property
    def td_error(self) -> float:
        return self.target - self.before


@dataclass(frozen=True)
class Transition:
    """One transition between table rows, as a learner learned from it."""

    state: int
    action: int
    reward: float
    next_state: int
    terminated: bool
    truncated: bool
    next_action: int | None
    epsilon: float


@dataclass(frozen=True)
class UpdateRecord:
    """How a learner used one transition: what the step-by-step view shows.

    `formula` is the target as written, `terms` its symbols with their values;
    `target`, `td_error` and `step_size` are None while nothing is updated (Monte
    Carlo mid-episode). `target_action`: the action in s' the target reads, if one.
    `episode_updates`: the other pairs moved (Monte Carlo, traces); `notes`: more
    (label, text) lines (the n-step window, the traces, the queue).
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
    notes: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class TableSpec:
    """One per-(state, action) table a learner keeps: its name, dtype and initial value."""

    name: str
    dtype: type
    fill: float | int | bool = 0


_VISITS = TableSpec("visits", np.int64)  # updates per state: saved and checked as a table is


@dataclass(frozen=True)
class Extra:
    """An array a rule takes after the tables and `visits`. `size`: "rows", "table" or
    "cells" (growing with the table), "episode" (doubled by `make_room`), a
    hyperparameter's name or a number. `fill` None: `initial_value`."""

    name: str
    size: str | int
    dtype: type = np.float64
    fill: float | int | None = 0


@dataclass(frozen=True)
class LearnerState:
    """Everything a learner saves: named arrays (the used rows), JSON-able `meta`, and each
    row's key for a sparse table (None: dense)."""

    algorithm: str
    arrays: dict[str, np.ndarray]
    meta: dict[str, Any]
    keys: list[Hashable] | None = None


class Learner(ABC):
    """A tabular learner over `n_actions` actions: a dense table of `n_states` rows, or
    (None) one that grows as keys come; `seed` seeds its one generator."""

    name: ClassVar[str]  # the registry name: `--algorithm NAME`, save files
    title: ClassVar[str]  # how a person reads it
    summary: ClassVar[str]  # one line: what it teaches
    formula: ClassVar[str]  # its target, as the step-by-step view writes it
    params: ClassVar[tuple[Field, ...]] = COMMON_PARAMS
    tables: ClassVar[tuple[TableSpec, ...]] = (
        TableSpec("q", np.float64), TableSpec("counts", np.int64),
    )
    value_tables: ClassVar[tuple[str, ...]] = ("q",)  # start at `initial_value`
    extras: ClassVar[tuple[Extra, ...]] = ()
    has_traces: ClassVar[bool] = False  # keeps eligibility traces (`eligibility`)
    rule: ClassVar[rules.Rule]  # its compiled parts (see `rules`)
    Params: ClassVar[Any]  # the NamedTuple of its compiled hyperparameters (`__init_subclass__`)
    # The tables named in `tables` (these two for most learners) are attributes.
    q: np.ndarray
    counts: np.ndarray

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """A learner with a `rule` of its own gets its own `Params` (the rule's key)."""
        super().__init_subclass__(**kwargs)
        if "rule" not in vars(cls):
            return
        common = {f.name for f in COMMON_PARAMS}
        fields = [("learning_rate", float), ("discount", float), ("by_visits", bool)] + [
            ("replacing", bool) if f.name == "traces" else
            (f.name + "_" * keyword.iskeyword(f.name), f.kind)
            for f in cls.params if f.name not in common]
        params: Any = NamedTuple("Params", fields)  # type: ignore[misc]
        params.__module__, params.__qualname__ = cls.__module__, f"{cls.__qualname__}.Params"
        cls.Params = params
        rules.register(params, cls.rule)

    def __init__(
        self, n_actions: int, hyperparameters: Mapping[str, Any] | None = None, *,
        n_states: int | None = None, seed: int | None = None,
    ) -> None:
        if n_actions < 1:
            raise ValueError(f"n_actions must be >= 1, got {n_actions}")
        if n_states is not None and n_states < 1:
            raise ValueError(f"n_states must be >= 1, got {n_states}")
        self.n_actions = int(n_actions)
        self.n_states = None if n_states is None else int(n_states)
        self.hp = self.settings(hyperparameters)
        self._params: Any = None
        self.rng = np.random.default_rng(seed)
        self.episode = 0  # episodes finished; drives the epsilon schedule
        self.epsilon = self.hp.epsilon_at(0)
        self._last: tuple[Transition, np.ndarray] | None = None  # see `last_update`
        self._last_record: UpdateRecord | None = None
        self.offered: np.ndarray | None = None  # see `offer`
        self.offered_ranges = rules.offered_ranges(None, self.n_actions)
        self._index: dict[Hashable, int] | None = None if n_states is not None else {}
        capacity = self.n_states if self.n_states is not None else _INITIAL_ROWS
        self.rows_used = self.n_states if self.n_states is not None else 0
        self.visits = np.zeros(capacity, dtype=np.int64)  # updates per state
        for spec in self.tables:
            setattr(self, spec.name,
                    np.full((capacity, self.n_actions), self._fill(spec), spec.dtype))
        self._make_extra(capacity)

    def _fill(self, spec: TableSpec, hp: Settings | None = None) -> float | int | bool:
        """What a new row of a table holds: `initial_value` for the values, else its fill."""
        if spec.name not in self.value_tables:
            return spec.fill
        return (self.hp if hp is None else hp).initial_value

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

    # --- what a subclass may write -------------------------------------------------------
    def arrays(self) -> tuple[np.ndarray, ...]:
        """What the compiled rule takes, in its order: the tables, `visits`, the extras."""
        return (*(getattr(self, spec.name) for spec in self.tables), self.visits,
                *(getattr(self, extra.name) for extra in self.extras))

    def action_values(self, rows: np.ndarray | slice) -> np.ndarray:
        """The values shown and evaluated, per row (k, n_actions); the policy's best."""
        return self.q[rows]

    def eligibility(self) -> np.ndarray | None:
        """The episode's eligibility traces shaped as `table()`'s values (a copy), or None."""
        return None

    def _shape(self, extra: Extra, capacity: int) -> tuple[int, ...]:
        size = extra.size
        if isinstance(size, int):
            return (size,)
        shapes = {"rows": (capacity,), "table": (capacity, self.n_actions),
                  "cells": (capacity * self.n_actions,), "episode": (_FIRST_STEPS,)}
        return shapes[size] if size in shapes else (int(self.hp[size]),)

    def _new(self, extra: Extra, shape: tuple[int, ...]) -> np.ndarray:
        return np.full(shape, self.hp.initial_value if extra.fill is None else extra.fill,
                       extra.dtype)

    def _make_extra(self, capacity: int) -> None:
        """The extras, for `capacity` rows."""
        for extra in self.extras:
            setattr(self, extra.name, self._new(extra, self._shape(extra, capacity)))

    def log_rows(self) -> int:
        """Rows of log an explained update of the next transition may write."""
        return 1

    def make_room(self) -> None:
        """Room the rule asked for (`rules.full`): twice the room for the episode."""
        for extra in self.extras:
            if extra.size == "episode":
                old = getattr(self, extra.name)
                setattr(self, extra.name, np.concatenate([old, np.zeros_like(old)]))

    def _extra_arrays(self) -> dict[str, np.ndarray]:
        """Arrays to save beyond the tables (copies)."""
        return {}

    def _load_extra_arrays(self, arrays: Mapping[str, np.ndarray], rows: int,
                           capacity: int) -> None:
        """Check what `_extra_arrays` saved (ValueError first), then make the extras."""
        self._make_extra(capacity)

    @abstractmethod
    def _describe(self, step: Transition, log: np.ndarray) -> UpdateRecord:
        """The record of one update from the numbers its rule wrote into `log`."""

    # --- the compiled side ---------------------------------------------------------------
    def compiled_params(self) -> Any:
        """The compiled hyperparameters (`Params`) of the current settings."""
        if self._params is None:
            hp = self.hp
            derived = {"by_visits": hp.learning_rate_schedule == "visits",
                       "replacing": hp.get("traces") == "replacing"}
            self._params = self.Params(**{  # the others from their settings (`lambda_`: `lambda`)
                name: derived[name] if name in derived else kind(hp[name.rstrip("_")])
                for name, kind in self.Params.__annotations__.items()})
            self._exploration = np.array([hp.epsilon_start, hp.epsilon_final,
                                          hp.epsilon_decay_fraction * hp.episodes])
        return self._params

    def exploration(self) -> np.ndarray:
        """(epsilon start, final, episodes of the decay) for the compiled schedule."""
        self.compiled_params()
        return self._exploration

    def offer(self, offered: np.ndarray | None) -> None:
        """The actions each row of a dense table offers (`[n_states, n_actions]` bool, one
        run a row; a row offering none offers all), or None: all."""
        mask = None
        if offered is not None:
            mask = np.array(offered, dtype=np.bool_)
            if self.n_states is None or mask.shape != (self.n_states, self.n_actions):
                raise ValueError(f"offered actions of shape {mask.shape} do not fit a table "
                                 f"of {self.n_states} states and {self.n_actions} actions")
            mask[~mask.any(axis=1)] = True
        self.offered = None if mask is None or mask.all() else mask
        self.offered_ranges = rules.offered_ranges(self.offered, self.n_actions)

    @property
    def next_first(self) -> bool:
        """Whether the rule needs the next action before its update (SARSA)."""
        return rules.next_first(self.compiled_params())

    def begin_episode(self) -> None:
        """An episode starts: whatever was kept of an unfinished one goes."""
        rules.begin(self.arrays(), self.compiled_params())

    def learn(
        self, state: int, action: int, reward: float, next_state: int, terminated: bool,
        truncated: bool = False, next_action: int = -1, explain: bool = False,
    ) -> tuple[int, float]:
        """One transition between rows through the compiled rule: (the next action, |TD
        error|). With `explain`, `last_update` explains it."""
        if rules.full(self.arrays(), self.compiled_params()):
            self.make_room()
        log = rules.new_log(self.log_rows() if explain else 1)
        hp = self.compiled_params()
        a2, td = loop.entries(hp).transition(
            self.arrays(), hp, self.rng, self.offered_ranges, int(state), int(action),
            float(reward), int(next_state), bool(terminated), bool(truncated), int(next_action),
            float(self.epsilon), log,
        )
        if explain:
            picked = int(a2) if int(a2) >= 0 else None
            self._last = (Transition(int(state), int(action), float(reward), int(next_state),
                                     bool(terminated), bool(truncated), picked,
                                     float(self.epsilon)), log)
            self._last_record = None
        else:
            self._last = None
        return int(a2), float(td)

    def update_one(
        self, key: Hashable, action: int, reward: float, next_key: Hashable, terminated: bool,
        truncated: bool = False, next_action: int | None = None,
    ) -> float:
        """One transition by observation keys (SARSA's takes `next_action`), explained in
        `last_update`; its |TD error|."""
        if self.next_first and next_action is None and not terminated:
            raise ValueError(f"{self.title} needs the next action of a transition (next_action)")
        state, next_state = self.row(key), self.row(next_key)
        return self.learn(state, action, reward, next_state, terminated, truncated,
                          -1 if next_action is None else next_action, explain=True)[1]

    # --- rows ----------------------------------------------------------------------
    @property
    def dense(self) -> bool:
        return self._index is None

    def row(self, key: Hashable) -> int:
        """The table row of a key, adding one for a new sparse key."""
        index = self._index
        if index is None:
            return key  # type: ignore[return-value]
        row = index.get(key)
        if row is None:
            row = self.rows_used
            if row == len(self.visits):
                self._grow()
            index[key] = row
            self.rows_used += 1
        return row

    def find(self, key: Hashable) -> int | None:
        """The row of a key, or None when a sparse table has never seen it."""
        if self._index is None:
            return key  # type: ignore[return-value]
        return self._index.get(key)

    def _grow(self) -> None:
        """Twice the rows: the tables, `visits` and the extras that grow with them."""
        for spec in (_VISITS, *self.tables):
            old = getattr(self, spec.name)
            setattr(self, spec.name, np.concatenate([old, np.full_like(old, self._fill(spec))]))
        for extra in self.extras:
            if extra.size in ("rows", "table", "cells"):
                old = getattr(self, extra.name)
                setattr(self, extra.name, np.concatenate([old, self._new(extra, old.shape)]))

    # --- acting ----------------------------------------------------------------------
    def act(self, key: Hashable) -> int:
        """Epsilon-greedy in a state, ties broken at random (the engine's own draws)."""
        hp = self.compiled_params()
        return int(loop.entries(hp).act(self.arrays(), hp, self.rng, self.offered_ranges,
                                        self.row(key), float(self.epsilon)))

    def greedy(self, key: Hashable) -> int:
        """The best-valued action in a state, ties broken at random."""
        hp = self.compiled_params()
        return int(loop.entries(hp).greedy(self.arrays(), hp, self.rng, self.offered_ranges,
                                           self.row(key)))

    def greedy_actions(self, key: Hashable) -> tuple[int, ...]:
        """Every action tied for the best value among those a state offers."""
        values = self.values([key])[0]
        row = self.find(key)
        if self.offered is not None and row is not None:
            values = np.where(self.offered[row], values, -np.inf)
        return tuple(int(a) for a in np.flatnonzero(values == values.max()))

    # --- the schedule ------------------------------------------------------------------
    def end_episodes(self, count: int = 1) -> None:
        """Count finished episodes and move epsilon along its schedule."""
        self.episode += count
        self.epsilon = self.hp.epsilon_at(self.episode)

    def set_hyperparameters(self, hyperparameters: Mapping[str, Any]) -> None:
        """New values for the rest of the run, taking effect at once; tables and episodes stay."""
        self.hp = self.settings(hyperparameters)
        self._params = None
        self.epsilon = self.hp.epsilon_at(self.episode)

    # --- reading the table ----------------------------------------------------------------
    def values(self, keys: Iterable[Hashable]) -> np.ndarray:
        """Action values for many states (unseen ones hold the initial value)."""
        keys = list(keys)
        out = np.full((len(keys), self.n_actions), float(self.hp.initial_value))
        found = [(i, row) for i, key in enumerate(keys) if (row := self.find(key)) is not None]
        if found:
            at, rows = zip(*found, strict=True)
            out[list(at)] = self.action_values(np.asarray(rows, dtype=np.int64))
        return out

    def table(self) -> tuple[np.ndarray, list[Hashable] | None]:
        """The action values of the used rows and, for sparse tables, each row's key."""
        values = self.action_values(slice(0, self.rows_used))
        return values.copy(), self._keys()

    def _keys(self) -> list[Hashable] | None:
        if self._index is None:
            return None
        keys: list[Hashable] = [None] * self.rows_used
        for key, row in self._index.items():
            keys[row] = key
        return keys

    def update_counts(self) -> np.ndarray:
        """Updates per (state, action) of the used rows."""
        return self.counts[: self.rows_used].copy()

    def seen(self, key: Hashable) -> bool:
        """Whether the learner has updated this state at least once."""
        row = self.find(key)
        return row is not None and bool(self.visits[row])

    @property
    def states_seen(self) -> int:
        """How many states have been updated at least once."""
        return int(np.count_nonzero(self.visits[: self.rows_used]))

    # --- the record of one update ---------------------------------------------------------
    @property
    def last_update(self) -> UpdateRecord | None:
        """How the latest explained update used its transition."""
        if self._last is None:
            return None
        if self._last_record is None:
            self._last_record = self._describe(*self._last)
        return self._last_record

    def _record(
        self, step: Transition, formula: str, terms: tuple[tuple[str, float], ...],
        target: float | None, before: float, after: float, alpha: float | None = None, **extra: Any,
    ) -> UpdateRecord:
        """An `UpdateRecord` for one transition (no step size when there is no target)."""
        return UpdateRecord(
            algorithm=self.name, state=step.state, action=step.action, reward=step.reward,
            next_state=step.next_state, next_action=step.next_action, terminated=step.terminated,
            truncated=step.truncated, formula=formula, terms=terms,
            target=None if target is None else float(target),
            td_error=None if target is None else float(target) - float(before),
            step_size=None if target is None else alpha, before=float(before), after=float(after),
            **extra,
        )

    @staticmethod
    def _logged(rows: np.ndarray) -> tuple[CellUpdate, ...]:
        """The updates logged in `rows` (as `note` writes them)."""
        return tuple(CellUpdate(int(w[0]), int(w[1]), *(float(x) for x in w[2:6])) for w in rows)

    def _td_record(self, step: Transition, log: np.ndarray, future_term: str,
                   *more: tuple[str, float], formula: str = "", **extra: Any) -> UpdateRecord:
        """The record of a one-step TD update logged by `rules.td_update`."""
        target, future, before, after, alpha = (float(v) for v in log[0, :5])
        terms: tuple[tuple[str, float], ...] = (("r", step.reward),)
        if not step.terminated:
            terms += (("γ", self.hp.discount), *more, (future_term, future))
        written = "r" if step.terminated else formula or self.formula
        return self._record(step, written, terms, target, before, after, alpha, **extra)

    # --- saving ------------------------------------------------------------------------------
    def _check_arrays(self, arrays: Mapping[str, np.ndarray], rows: int) -> None:
        """ValueError, naming the array, for a saved table missing or holding values this
        learner could not have made."""
        for spec in (_VISITS, *self.tables):
            if spec.name not in arrays:
                raise ValueError(f"the saved state has no {spec.name!r} array")
            array = np.asarray(arrays[spec.name])
            shape = (rows,) if spec is _VISITS else (rows, self.n_actions)
            if array.shape != shape:
                raise ValueError(f"saved {spec.name!r} has shape {array.shape}, expected {shape}")
            want = np.dtype(spec.dtype).kind  # bool, float (read from any number) or integer
            if array.dtype.kind not in {"b": "b", "f": "fiu"}.get(want, "iu"):
                raise ValueError(f"saved {spec.name!r} holds {array.dtype} values")
            if want == "f" and not np.isfinite(array).all():
                raise ValueError(f"saved {spec.name!r} holds NaN or infinite values")
            low = min(0, int(spec.fill))
            if want in "iu" and array.size and (array.min() < low
                                                or array.max() > MAX_SAVED_COUNT):
                raise ValueError(f"saved {spec.name!r} holds negative or impossible counts")

    def state(self) -> LearnerState:
        """Copies of everything that defines this learner, to save or send elsewhere."""
        used = self.rows_used
        arrays = {spec.name: getattr(self, spec.name)[:used].copy()
                  for spec in (_VISITS, *self.tables)} | self._extra_arrays()
        meta = {
            "algorithm": self.name, "n_actions": self.n_actions, "n_states": self.n_states,
            "rows": used, "episode": self.episode, "hyperparameters": self.hp.to_dict(),
        }
        return LearnerState(self.name, arrays, meta, self._keys())

    def load_state(self, state: LearnerState) -> None:
        """Become the learner `state` describes (the generator is kept); ValueError,
        changing nothing, when it is another algorithm's or does not fit."""
        if state.algorithm != self.name:
            raise ValueError(f"this is a {state.algorithm} learner's state, not {self.name}'s")
        meta, arrays = state.meta, state.arrays
        rows = int(meta.get("rows", -1))
        if int(meta.get("n_actions", -1)) != self.n_actions:
            raise ValueError(f"the saved table has {meta.get('n_actions')} actions, "
                             f"this one {self.n_actions}")
        dense = state.keys is None
        if dense != self.dense:
            kinds = ("sparse", "dense")
            raise ValueError(f"the saved table is {kinds[dense]}, this one {kinds[self.dense]}")
        if dense and rows != self.n_states:
            raise ValueError(f"the saved table has {rows} states, this one {self.n_states}")
        if not dense and len(state.keys) != rows:  # type: ignore[arg-type]
            raise ValueError("sparse table keys and rows differ in number")
        hp = self.settings(meta.get("hyperparameters"))
        self._check_arrays(arrays, rows)
        capacity = rows if dense else max(_INITIAL_ROWS, rows)
        loaded: dict[str, np.ndarray] = {}
        for spec in (_VISITS, *self.tables):
            saved = np.asarray(arrays[spec.name])
            loaded[spec.name] = np.full((capacity, *saved.shape[1:]), self._fill(spec, hp),
                                        spec.dtype)
            loaded[spec.name][:rows] = saved
        self._load_extra_arrays(arrays, rows, capacity)
        vars(self).update(loaded)
        self.rows_used = rows
        self._index = None if dense else {k: i for i, k in enumerate(state.keys)}  # type: ignore[arg-type]
        self.hp = hp
        self._params = None
        self.episode = int(meta.get("episode", 0))
        self.epsilon = hp.epsilon_at(self.episode)
        self._last = self._last_record = None

    @classmethod
    def from_state(cls, state: LearnerState, seed: int | None = None) -> Learner:
        """A new learner of this class restored from `state`."""
        meta = state.meta
        learner = cls(
            int(meta["n_actions"]), meta.get("hyperparameters"),
            n_states=None if state.keys is not None else int(meta["rows"]), seed=seed,
        )
        learner.load_state(state)
        return learner

    def assign_from(self, other: Learner) -> None:
        """Become a copy of `other` (tables, schedule, generator), keeping identity."""
        if type(other) is not type(self):
            raise ValueError(f"cannot take over a {other.name} learner as {self.name}")
        if other.n_actions != self.n_actions or other.n_states != self.n_states:
            raise ValueError("cannot take over a learner of a different shape")
        vars(self).update(vars(other))

    def __repr__(self) -> str:
        shape = f"{self.n_states} states" if self.n_states is not None else "sparse"
        return f"{type(self).__name__}({shape}, {self.n_actions} actions, episode {self.episode})"
