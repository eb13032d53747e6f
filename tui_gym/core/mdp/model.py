"""`FiniteMDP`: a game's exact model as dense transition arrays; the model under a time
limit; `Phases`, a world that changes as it is played."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import numpy.typing as npt

PROBABILITY_TOLERANCE = 1e-9
"""How far a distribution's total may stray from 1 (round-off in tables like 0.8 + 0.1 + 0.1)."""

Outcome = tuple[float, int, float, bool]
"""One outcome of a state-action pair: (probability, next state, reward, terminated)."""

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


class ModelError(ValueError):
    """Arrays or a table that do not make a finite MDP; the message says where and why."""


def _refuse(bad: np.ndarray, what: str) -> None:
    """ModelError naming the first state and action where `bad` (`[S, A, K]`) holds."""
    if bad.any():
        s, a, _ = np.argwhere(bad)[0]
        raise ModelError(f"state {s}, action {a} {what}")


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class FiniteMDP:
    """A finite MDP with S states, A actions and at most K outcomes per state-action pair:
    `[S, A, K]` arrays `next_state`, `prob` (each `[s, a]` summing to 1), `reward`,
    `terminal` and `reward_std` (a normal deviation around `reward`, or None); `initial`
    `[S]`; `horizon`, the episode limit or None. Arrays are copied, checked (`ModelError`)
    and made read-only."""

    next_state: IntArray
    prob: FloatArray
    reward: FloatArray
    terminal: BoolArray
    initial: FloatArray
    horizon: int | None = None
    action_names: tuple[str, ...] | None = None
    reward_std: FloatArray | None = None

    def __post_init__(self) -> None:
        prob = np.array(self.prob, dtype=np.float64)
        if prob.ndim != 3 or 0 in prob.shape:
            raise ModelError(f"prob must be a non-empty [S, A, K] array, got shape {prob.shape}")
        shape = n_states, n_actions, _ = prob.shape
        arrays: dict[str, np.ndarray | None] = {"prob": prob, "reward_std": None}
        for name, dtype in (
            ("next_state", None),
            ("reward", np.float64),
            ("terminal", None),
            ("reward_std", np.float64),
        ):
            given = getattr(self, name)
            if given is None:  # only `reward_std` may be
                continue
            array = arrays[name] = np.array(given, dtype=dtype)
            if array.shape != shape:
                raise ModelError(f"{name} has shape {array.shape}, prob has {shape}")
        next_state, reward, terminal = arrays["next_state"], arrays["reward"], arrays["terminal"]
        assert next_state is not None and reward is not None and terminal is not None
        if not np.issubdtype(next_state.dtype, np.integer):
            raise ModelError(f"next_state must hold integers, got dtype {next_state.dtype}")
        _refuse(
            (next_state < 0) | (next_state >= n_states),
            f"leads to a state outside [0, {n_states - 1}]",
        )
        if terminal.dtype != np.bool_:
            raise ModelError(f"terminal must hold booleans, got dtype {terminal.dtype}")
        _refuse(~np.isfinite(reward), "has a reward that is not finite")
        _refuse(~(prob >= 0) | ~np.isfinite(prob), "has a probability that is not in [0, 1]")
        totals = prob.sum(axis=2)
        bad = np.abs(totals - 1.0) > PROBABILITY_TOLERANCE
        if bad.any():
            s, a = np.argwhere(bad)[0]
            raise ModelError(
                f"the probabilities of state {s}, action {a} sum to {totals[s, a]:.12g}, not 1"
            )
        std = arrays["reward_std"]
        if std is not None:
            _refuse(
                ~(std >= 0) | ~np.isfinite(std),
                "has a reward deviation that is not a finite number >= 0",
            )
        initial = arrays["initial"] = np.array(self.initial, dtype=np.float64)
        if initial.shape != (n_states,):
            raise ModelError(f"initial must have shape ({n_states},), got {initial.shape}")
        if not np.isfinite(initial).all() or (initial < 0).any():
            raise ModelError("initial must hold probabilities in [0, 1]")
        if abs(initial.sum() - 1.0) > PROBABILITY_TOLERANCE:
            raise ModelError(f"initial sums to {initial.sum():.12g}, not 1")
        horizon = self.horizon
        if horizon is not None:
            if isinstance(horizon, bool) or not isinstance(horizon, int | np.integer):
                raise ModelError(f"horizon must be an integer or None, got {horizon!r}")
            if horizon < 1:
                raise ModelError(f"horizon must be >= 1 step, got {horizon}")
            horizon = int(horizon)
        names = self.action_names
        if names is not None:
            names = tuple(str(name) for name in names)
            if len(names) != n_actions:
                raise ModelError(f"{len(names)} action names for {n_actions} actions")
        arrays["next_state"] = next_state.astype(np.int64)
        for name, value in arrays.items():
            object.__setattr__(self, name, None if value is None else _frozen(value))
        object.__setattr__(self, "horizon", horizon)
        object.__setattr__(self, "action_names", names)

    # -- sizes ------------------------------------------------------------------

    @property
    def n_states(self) -> int:
        return int(self.prob.shape[0])

    @property
    def n_actions(self) -> int:
        return int(self.prob.shape[1])

    @property
    def max_outcomes(self) -> int:
        """K: the most outcomes any state-action pair has."""
        return int(self.prob.shape[2])

    # -- derived arrays, computed once --------------------------------------------

    @cached_property
    def expected_reward(self) -> FloatArray:
        """`[S, A]`: the expected reward of one step."""
        return _frozen((self.prob * self.reward).sum(axis=2))

    @cached_property
    def continue_prob(self) -> FloatArray:
        """`[S, A, K]`: each outcome's probability where it does not end the episode, else 0."""
        return _frozen(np.where(self.terminal, 0.0, self.prob))

    @cached_property
    def cumulative(self) -> FloatArray:
        """`[S, A, K]`: the running total of `prob`, exactly 1 from each row's last outcome on."""
        cumulative = np.cumsum(self.prob, axis=2)
        possible = self.prob > 0
        # Index of each row's last possible outcome: from there on the total is 1 exactly,
        # so a uniform draw in [0, 1) never falls past it because of round-off.
        last = self.max_outcomes - 1 - np.argmax(possible[:, :, ::-1], axis=2)
        after = np.arange(self.max_outcomes) >= last[:, :, None]
        cumulative[after] = 1.0
        return _frozen(cumulative)

    # -- reading and rebuilding -----------------------------------------------------

    def outcomes(self, state: int, action: int) -> list[Outcome]:
        """The possible outcomes of one state-action pair, padding left out."""
        row = self.prob[state, action] > 0
        columns = (
            array[state, action][row]
            for array in (self.prob, self.next_state, self.reward, self.terminal)
        )
        return [(float(p), int(s), float(r), bool(t)) for p, s, r, t in zip(*columns, strict=True)]

    def replace(self, **changes: Any) -> FiniteMDP:
        """A copy with some fields replaced (checked again)."""
        unknown = set(changes) - {field.name for field in dataclasses.fields(self)}
        if unknown:
            raise TypeError(f"FiniteMDP has no field {', '.join(sorted(unknown))}")
        return dataclasses.replace(self, **changes)

    @classmethod
    def from_table(
        cls,
        table: Mapping[int, Mapping[int, Iterable[Sequence[Any]]]]
        | Sequence[Sequence[Iterable[Sequence[Any]]]],
        initial: Sequence[float] | np.ndarray,
        *,
        n_states: int | None = None,
        n_actions: int | None = None,
        horizon: int | None = None,
        action_names: Sequence[str] | None = None,
    ) -> FiniteMDP:
        """Build a model from `table[s][a] = [(prob, next_state, reward, terminated), ...]`,
        merging equal outcomes and dropping those of probability 0 (`ModelError` for a
        missing state or action, or a malformed outcome)."""
        n_states = len(table) if n_states is None else n_states
        if n_states < 1:
            raise ModelError("the table has no states")
        rows: list[list[list[Outcome]]] = []
        for s in range(n_states):
            try:
                actions = table[s]
            except (KeyError, IndexError):
                raise ModelError(f"the table has no entry for state {s}") from None
            if n_actions is None:
                n_actions = len(actions)
            if n_actions < 1:
                raise ModelError(f"state {s} has no actions")
            row: list[list[Outcome]] = []
            for a in range(n_actions):
                try:
                    listed = actions[a]
                except (KeyError, IndexError):
                    raise ModelError(f"the table has no entry for state {s}, action {a}") from None
                row.append(_merged(listed, s, a))
            rows.append(row)
        assert n_actions is not None
        width = max(len(outcomes) for row in rows for outcomes in row)
        shape = (n_states, n_actions, width)
        next_state = np.broadcast_to(np.arange(n_states)[:, None, None], shape).copy()
        prob = np.zeros(shape)
        reward = np.zeros(shape)
        terminal = np.zeros(shape, dtype=bool)
        for s, row in enumerate(rows):
            for a, outcomes in enumerate(row):
                for k, (p, nxt, r, t) in enumerate(outcomes):
                    prob[s, a, k], next_state[s, a, k] = p, nxt
                    reward[s, a, k], terminal[s, a, k] = r, t
        return cls(
            next_state=next_state,
            prob=prob,
            reward=reward,
            terminal=terminal,
            initial=np.asarray(initial, dtype=np.float64),
            horizon=horizon,
            action_names=None if action_names is None else tuple(action_names),
        )


def _merged(listed: Iterable[Sequence[Any]], state: int, action: int) -> list[Outcome]:
    merged: dict[tuple[int, float, bool], float] = {}
    try:
        for outcome in listed:
            if len(outcome) != 4:
                raise TypeError(
                    f"an outcome must be (prob, next_state, reward, terminated), got {outcome!r}"
                )
            p, nxt, r, t = float(outcome[0]), int(outcome[1]), float(outcome[2]), bool(outcome[3])
            if p != 0.0:
                merged[nxt, r, t] = merged.get((nxt, r, t), 0.0) + p
    except (TypeError, ValueError) as error:
        raise ModelError(f"state {state}, action {action}: {error}") from None
    if not merged:
        raise ModelError(f"state {state}, action {action} has no possible outcome")
    return [(p, nxt, r, t) for (nxt, r, t), p in merged.items()]


def with_horizon(model: FiniteMDP, horizon: int | None) -> FiniteMDP:
    """The model with the episode cut off after `horizon` steps (None: no limit)."""
    return model.replace(horizon=horizon)


@dataclass(frozen=True, eq=False)
class Phases:
    """The model of each phase (`models[i]` from step `starts[i]` on); `ModelError` when the
    phases do not make one world (a first start other than 0, starts not increasing, or
    models of different sizes)."""

    models: tuple[FiniteMDP, ...]
    starts: tuple[int, ...]

    def __post_init__(self) -> None:
        models, starts = tuple(self.models), tuple(int(s) for s in self.starts)
        if not models or len(models) != len(starts):
            raise ModelError(f"{len(models)} models for {len(starts)} phase starts")
        if starts[0] != 0 or any(b <= a for a, b in zip(starts, starts[1:], strict=False)):
            raise ModelError(f"phases must start at step 0 and then later each, got {starts}")
        sizes = {(m.n_states, m.n_actions) for m in models}
        if len(sizes) > 1:
            raise ModelError(f"the phases' models differ in size: {sorted(sizes)}")
        object.__setattr__(self, "models", models)
        object.__setattr__(self, "starts", starts)
