"""Games with an exact model: the oracle every finite game shares. Optimal are the quickest
actions of optimal value (best again discounted by `TIE_GAMMA`); the others `Advice.equal`.
"""

from __future__ import annotations

import threading
from bisect import bisect_right
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp import (
    TIE_GAMMA,
    FiniteMDP,
    Ladder,
    NotAvailable,
    Phases,
    evaluate,
    gap_of,
    greedy_policy,
    model_from_env,
    return_range,
    solve,
    with_horizon,
)
from tui_gym.core.mdp.evaluation import expected_value
from tui_gym.core.wrappers import build_env
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.games.base import (
    EXACT,
    UNREADABLE,
    Advice,
    Bound,
    FixedBound,
    Game,
    Optimum,
    Oracle,
    ReferenceMetrics,
    Scope,
    StateSpace,
    TrainingModel,
)
from tui_gym.games.planning import PlanModel
from tui_gym.games.words import signed, unwrapped_note

__all__ = [
    "PHASE", "TIE_GAMMA", "DiscreteStates", "ModelGame", "ModelOracle", "Ladder", "elapsed_steps",
    "freeze", "table_model",
]

PHASE = "phase"  # the argument naming a changing world's phase, for its exact figures
SEARCH_LIMIT = 4096  # state-action pairs a fixed-policy search looks at, at most

BoolArray = npt.NDArray[np.bool_]
FloatArray = npt.NDArray[np.float64]


def freeze(value: Any) -> Any:
    """Arguments as a hashable key: dicts and lists become sorted tuples."""
    if isinstance(value, Mapping):
        return tuple(sorted((str(k), freeze(v)) for k, v in value.items()))
    if isinstance(value, list | tuple):
        return tuple(freeze(v) for v in value)
    if isinstance(value, np.ndarray):
        return freeze(value.tolist())
    return value


@lru_cache(maxsize=32)
def table_model(env_id: str, frozen: Any = (), names: tuple[str, ...] = ()) -> (
        FiniteMDP | NotAvailable):
    """The model of `build_env(env_id, **frozen)`'s table, unwrapped, with no episode limit
    (kept); `frozen` as `freeze` makes it, `names` the actions' when they fit."""
    import gymnasium as gym

    kwargs = {k: _thaw(v) for k, v in frozen}
    kwargs.pop("max_episode_steps", None)
    try:
        env = build_env(env_id, kwargs)
    except (gym.error.Error, TypeError, ValueError, ImportError, AttributeError) as error:
        return NotAvailable(f"{env_id} could not be built: {' '.join(str(error).split())}")
    try:
        n = getattr(env.action_space, "n", None)
        action_names = names if n is not None and len(names) == int(n) else None
        return model_from_env(env.unwrapped, horizon=None, action_names=action_names)
    finally:
        env.close()


def _thaw(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_thaw(v) for v in value]
    return value


def elapsed_steps(env: Any) -> int | None:
    """Steps taken this episode as the env's tightest `TimeLimit` counts them, or None."""
    from tui_gym.core.wrappers import chain

    limits = [(limit - chain.elapsed(layer), chain.elapsed(layer)) for layer in chain.layers(env)
              if (limit := chain.time_limit(layer)) is not None]  # (steps left, elapsed)
    return min(limits, key=lambda pair: pair[0])[1] if limits else None


@dataclass(frozen=True)
class _Exact:
    """A model with its optimum, kept per (arguments, wrappers)."""

    model: FiniteMDP
    ladder: Ladder
    scope: Scope

    @cached_property
    def value(self) -> float:
        """The optimum's value."""
        return expected_value(self.model, self.ladder.q().max(axis=1))

    @cached_property
    def fixed(self) -> FixedBound:
        """The best fixed policy a local search finds, beside the optimum."""
        return best_fixed_policy(self.model, self.value)


class DiscreteStates(StateSpace):
    """States that are the env's `Discrete` observations, one per model state."""

    game: ModelGame

    def base_observations(self, kwargs: Mapping[str, Any]) -> list[Any] | NotAvailable:
        model = self.game.base_model(kwargs)
        return model if isinstance(model, NotAvailable) else list(range(model.n_states))

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        return f"state {int(observation)}"


class ModelOracle(Oracle):
    """Exact figures from the game's model (see the module docstring)."""

    game: ModelGame

    def __init__(self, game: ModelGame) -> None:
        super().__init__(game)
        self._kept: dict[Any, _Exact | NotAvailable] = {}
        self._references: dict[Any, ReferenceMetrics] = {}  # per greedy policy
        self._lock = threading.Lock()  # the Train view's worker thread reads them too

    # --- the model as played ---------------------------------------------------
    def exact(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> _Exact | NotAvailable:
        """The model as the wrappers make it (or the unwrapped game's, when they change it
        beyond what a model follows: `scope` says so), with its optimum."""
        key = (freeze(kwargs), changes)
        found = self._kept.get(key)
        if found is None:
            found = self._keep(self._kept, 16, key, self._build(kwargs, changes))
        return found

    def _keep(self, memo: dict[Any, Any], size: int, key: Any, value: Any) -> Any:
        """Keep `value` in `memo` under `key`, the oldest going past `size`; `value`."""
        with self._lock:
            if len(memo) >= size:
                memo.pop(next(iter(memo)))
            memo[key] = value
        return value

    def _build(self, kwargs: Mapping[str, Any], changes: GameChanges) -> _Exact | NotAvailable:
        game = self.game
        base = game.base_model(kwargs)
        if isinstance(base, NotAvailable):
            return base
        unwrapped = unwrapped_note(changes.others) if changes.others else ""
        if not unwrapped:
            try:
                model = changes.model(base)
            except ValueError as error:
                unwrapped = f"figures of the unwrapped game: {error}"
        if unwrapped:
            model = with_horizon(base, game.episode_limit(kwargs))
            return _Exact(model, Ladder(model), Scope(False, unwrapped))
        notes = []
        if changes.changes_rewards:
            notes.append(changes.reward_names())
        if changes.chosen_time_limit and changes.time_limit is not None:
            notes.append(f"TimeLimit(max_episode_steps={changes.time_limit})")
        scope = Scope(True, f"exact with {', '.join(notes)}") if notes else EXACT
        return _Exact(model, Ladder(model), scope)

    def scope(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Scope:
        exact = self.exact(kwargs, changes)
        return Scope(False, exact.reason) if isinstance(exact, NotAvailable) else exact.scope

    # --- the greedy policy beside the optimum ------------------------------------
    def reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        exact = self.exact(kwargs, changes)
        if isinstance(exact, NotAvailable):
            return exact
        model = exact.model
        values = np.asarray(q, dtype=np.float64)
        if values.shape != (model.n_states, model.n_actions) or np.isnan(values).any():
            return NotAvailable(
                f"a table of shape {values.shape} does not fit {model.n_states} states "
                f"and {model.n_actions} actions"
            )
        offered = self.game.offered_actions(kwargs)
        if offered is not None and offered.shape == values.shape:  # greedy among those
            values = np.where(offered, values, -np.inf)
        # The figures follow from the greedy policy alone, which training changes less
        # often than the values: kept per policy.
        policy = greedy_policy(values)
        key = (freeze(kwargs), changes, policy.tobytes())
        found = self._references.get(key)
        if found is None:
            found = self._keep(self._references, 64, key,
                               self.policy_reference(policy, exact, kwargs, changes))
        return found

    def policy_reference(self, policy: FloatArray, exact: _Exact, kwargs: Mapping[str, Any],
                         changes: GameChanges) -> ReferenceMetrics:
        """The exact figures of `policy` (`[S, A]`, a greedy policy) beside the optimum."""
        model = exact.model
        value = evaluate(model, policy).value
        best = exact.value
        gap = gap_of(best, value)
        places = self.game.narrator.value_places
        return ReferenceMetrics(
            figures={"exact_value": value, "optimal_value": best, "gap": gap},
            summary=f"exact value {signed(value, places)}  optimum {signed(best, places)}  "
            f"gap {gap:.{places}f}",
            scope=exact.scope,
        )

    def agent_figures(
        self, q: np.ndarray | None, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> dict[str, float]:
        exact = self.exact(kwargs, changes)
        if isinstance(exact, NotAvailable):
            return {}
        if q is None:
            return {"optimal_value": exact.value}
        reference = self.reference(q, kwargs, changes)
        return {} if isinstance(reference, NotAvailable) else dict(reference.figures)

    # --- what to do here ----------------------------------------------------------
    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        changes = GameChanges.of(env, self.game.episode_limit(kwargs))
        exact = self.exact(kwargs, changes)
        if isinstance(exact, NotAvailable):
            return Advice((), None, exact.reason)
        state = self.game.state_of(env)
        model = exact.model
        if state is None or not 0 <= state < model.n_states:
            return Advice((), None, "no episode running")
        steps_left = None
        if model.horizon is not None:
            elapsed = elapsed_steps(env) or 0
            steps_left = model.horizon - elapsed
            if steps_left < 1:
                return Advice((), None, "no steps left")
        q = exact.ladder.q(steps_left)[state]
        best, quickest = (rows[state] for rows in exact.ladder.choices(steps_left))
        names = self.game.action_names
        values = {a: float(v) for a, v in enumerate(q)}
        optimal = tuple(int(a) for a in np.flatnonzero(quickest))
        equal = tuple(int(a) for a in np.flatnonzero(best & ~quickest))
        places = self.game.narrator.value_places
        listed = ", ".join(f"{names[a]} {signed(v, places)}" for a, v in values.items())
        chosen = " or ".join(names[a] for a in optimal)
        if not exact.scope.exact:
            why = exact.scope.note.removeprefix("figures of the unwrapped game: ")
            return Advice((), None, f"the unwrapped game's optimum: {chosen}  ({listed}; {why})",
                          unwrapped_optimal=optimal)
        return Advice(optimal, values, f"optimal: {chosen}  ({listed} expected)", equal=equal)

    def optimal_marks(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> BoolArray | NotAvailable:
        exact = self.exact(kwargs, changes)
        return exact if isinstance(exact, NotAvailable) else exact.ladder.choices()[1]

    def optimum(self, kwargs: Mapping[str, Any]) -> Optimum | NotAvailable:
        game = self.game
        exact = self.exact(kwargs, game.own_changes(kwargs))
        if isinstance(exact, NotAvailable):
            return exact
        horizon = exact.model.horizon
        limit = "no episode limit" if horizon is None else f"{horizon}-step episodes"
        return Optimum(
            value=exact.value,
            summary=f"the best expected return of an episode ({limit}, undiscounted)",
            q=exact.ladder.q(), marks=exact.ladder.choices()[1],
        )

    def bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> Bound | NotAvailable:
        """The gap within `gap_tolerance` of the optimum's magnitude, beyond what no
        fixed policy found reaches."""
        fixed = self.fixed_policy_bound(kwargs, changes)
        if isinstance(fixed, NotAvailable):
            return fixed
        share = self.game.gap_tolerance(kwargs)
        limit = fixed.shortfall + share * abs(fixed.optimal_value)
        text = f"gap <= {limit:.4g}"
        if share:
            text += f" ({share:.0%} of the optimum"
            text += f", beyond the best fixed policy's {fixed.shortfall:.4g})" if (
                fixed.shortfall) else ")"
        return Bound("gap", limit, text)

    def return_range(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> tuple[float, float] | NotAvailable:
        exact = self.exact(kwargs, changes)
        if isinstance(exact, NotAvailable):
            return exact
        if not exact.scope.exact:
            return NotAvailable(exact.scope.note)
        return return_range(exact.model)

    def fixed_policy_bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> FixedBound | NotAvailable:
        exact = self.exact(kwargs, changes)
        return exact if isinstance(exact, NotAvailable) else exact.fixed


def best_fixed_policy(model: FiniteMDP, optimal: float) -> FixedBound:
    """The best fixed policy a local search finds, beside the optimum's value: the best of
    the optimum's own and the unlimited optima (gamma 1, 0.999, 0.99), then improved by
    single-state changes (up to `SEARCH_LIMIT` state-action pairs)."""
    candidates = [solve(model).policy]
    if model.horizon is not None:
        free = with_horizon(model, None)
        for gamma in (1.0, 0.999, 0.99):
            try:
                candidates.append(solve(free, gamma).policy)
            except (RuntimeError, ValueError):  # no policy ends episodes surely
                continue
    values = [evaluate(model, np.asarray(p, dtype=np.int64)).value for p in candidates]
    best = int(np.argmax(values))
    value = values[best]
    searchable = model.horizon is not None and model.n_states * model.n_actions <= SEARCH_LIMIT
    if searchable and gap_of(optimal, value) != 0.0:
        value = _climb(model, np.asarray(candidates[best], dtype=np.int64), value)
    return FixedBound(optimal, value)


def _climb(model: FiniteMDP, policy: np.ndarray, value: float) -> float:
    """The value a hill-climb on single-state changes of a fixed policy reaches."""
    n_states, n_actions = model.n_states, model.n_actions
    states = np.repeat(np.arange(n_states), n_actions)
    actions = np.tile(np.arange(n_actions), n_states)
    for _ in range(10 * n_states):
        neighbours = np.broadcast_to(policy, (len(states), n_states)).copy()
        neighbours[np.arange(len(states)), states] = actions
        scores = _values_of(model, neighbours)
        best = int(np.argmax(scores))
        if not scores[best] > value + 1e-12:
            break
        policy, value = neighbours[best], float(scores[best])
    return value


def _values_of(model: FiniteMDP, policies: np.ndarray) -> FloatArray:
    """The exact values (over the model's limit) of many fixed policies `[C, S]` at once."""
    count, n_states = policies.shape
    rows = np.arange(n_states)[None, :]
    reward = model.expected_reward[rows, policies]  # [C, S]
    prob = model.continue_prob[rows, policies]  # [C, S, K]
    nxt = model.next_state[rows, policies]  # [C, S, K]
    v = np.zeros((count, n_states))
    which = np.arange(count)[:, None, None]
    for _ in range(model.horizon or 0):
        v = reward + (prob * v[which, nxt]).sum(axis=2)
    return v @ model.initial


class ModelGame(Game):
    """A game whose exact model is its env's transition table (or its own `base_model`)."""

    render_mode: str | None = "ansi"
    plan_gamma = 1.0  # the discount the Plan view starts with

    states_type: ClassVar[type[StateSpace]] = DiscreteStates
    oracle_type: ClassVar[type[Oracle]] = ModelOracle
    oracle: ModelOracle

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel | NotAvailable:
        model = self.base_model(kwargs)
        if isinstance(model, NotAvailable):
            return model
        return PlanModel(model, self.plan_gamma, self.episode_limit(kwargs),
                         offered=self.offered_actions(kwargs))

    def phase_starts(self, kwargs: Mapping[str, Any]) -> tuple[int, ...]:
        """The step (over episodes) each phase of the world starts at: one phase, from step
        0, for a world that never changes."""
        return (0,)

    def in_phase(self, kwargs: Mapping[str, Any], phase: int) -> dict[str, Any]:
        """The arguments of one phase of the world, for its exact figures."""
        if len(self.phase_starts(kwargs)) == 1:
            return dict(kwargs)
        return {**kwargs, PHASE: phase}

    def at_step(self, kwargs: Mapping[str, Any], steps: int) -> dict[str, Any]:
        starts = self.phase_starts(kwargs)
        return self.in_phase(kwargs, max(0, bisect_right(starts, int(steps)) - 1))

    def world(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> Phases | NotAvailable:
        """The model as the wrappers make it, phase by phase (one phase for a world that
        never changes), or why there is none that follows the game as played."""
        models = []
        for phase in range(len(self.phase_starts(kwargs))):
            exact = self.oracle.exact(self.in_phase(kwargs, phase), changes)
            if isinstance(exact, NotAvailable):
                return exact
            if not exact.scope.exact:
                return NotAvailable(exact.scope.note)
            models.append(exact.model)
        return Phases(tuple(models), self.phase_starts(kwargs))

    def offered_actions(self, kwargs: Mapping[str, Any]) -> BoolArray | None:
        """`[states, actions]`: the actions each state offers, for a game whose states do
        not all offer every action (None: every state offers every action)."""
        return None

    def base_model(self, kwargs: Mapping[str, Any]) -> FiniteMDP | NotAvailable:
        """The game's model with no wrappers and no episode limit (kept per arguments)."""
        make = self.make_kwargs(kwargs)
        return table_model(self.env_id, freeze(make), tuple(self.action_names))

    def gap_tolerance(self, kwargs: Mapping[str, Any]) -> float:
        """The share of the optimum's magnitude a trained greedy policy's gap stays within."""
        return 0.01

    def own_changes(self, kwargs: Mapping[str, Any]) -> GameChanges:
        """The game as `gym.make` builds it with no wrappers chosen: its own limit only."""
        return GameChanges(time_limit=self.episode_limit(kwargs))

    def state_of(self, env: Any) -> int | None:
        """The current state of a built env (None before the first reset)."""
        try:
            state = env.unwrapped.s
        except UNREADABLE:
            return None
        return None if state is None else int(state)

    def training_model(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> TrainingModel | NotAvailable:
        world = self.world(kwargs, changes)
        if isinstance(world, NotAvailable):
            return world
        return TrainingModel(world.models[0], later=tuple(
            zip(world.starts[1:], world.models[1:], strict=True)))
