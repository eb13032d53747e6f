"""Many seeds of one learner as one batch: one table per seed, stepped together in numpy.

`SeedBatch` trains N independent learners of one algorithm, each on its own
episode stream, for exactly E episodes each. The N tables are stacked in one
learner's table (seed i owns rows `i * S` to `(i + 1) * S`), so one batched
`act_batch` / `update` call serves every seed, and row i of every batch is
seed i's env. Nothing is shared between seeds but the numpy calls: a seed's
updates only touch its own rows, and each seed explores with the epsilon of
its own episode number (the schedule's value, per row), so every seed learns
as a learner of its own would, one transition at a time.

Seeds do not wait for each other: each starts its next episode as soon as
one ends, and leaves the batch after its E-th episode. A seed's per-episode
online returns go into row i of `returns`; where the game has an exact model,
its greedy policy is valued exactly each time it reaches a checkpoint.

The game comes as a `BatchedSteps`: `ModelSteps` for a finite model (the
model's own states are the keys; its episode limit truncates) or
`PlanSteps` for a game the vector engine plays through its wrapper plan.

Dyna-Q's planning draws from the pairs tried across the whole batch, so a
seed's share of planning updates is its share of the tried pairs, not
exactly its own count.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from tui_gym.algorithms import Learner, Settings, Transitions
from tui_gym.core.experiments.fast_batch import fast_rule, run_fast
from tui_gym.core.mdp import BatchSampler, FiniteMDP, evaluate

__all__ = [
    "BatchedSteps",
    "ModelSteps",
    "PlanSteps",
    "SeedBatch",
    "SeedBatchState",
    "checkpoint_episodes",
    "greedy_values",
]

MAX_CHECKPOINTS = 20  # exact valuations per seed over a run
_CHECK_EVERY = 32  # batch steps between looks at the clock and the stop flag


class BatchedSteps(Protocol):
    """A game's episodes, many at once: env i is seed i's; keys are table rows of one seed."""

    n_states: int
    n_actions: int

    def reset(self, envs: np.ndarray) -> np.ndarray:
        """Start an episode in each of `envs`; their first keys."""

    def step(
        self, envs: np.ndarray | None, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One move in each of `envs` (None: all): rewards, next keys, terminated, truncated."""


class ModelSteps:
    """Episodes of a `FiniteMDP`, truncated at its episode limit; keys are its states.

    Draws as `BatchSampler` does (one uniform number per row against the row's
    cumulative probabilities), and none for a model whose every move has one outcome.
    """

    def __init__(self, model: FiniteMDP, num_envs: int, seed: Any = None) -> None:
        self.model = model
        self.n_states = model.n_states
        self.n_actions = model.n_actions
        self.sampler = BatchSampler(model)
        self.rng = np.random.default_rng(seed)
        self.state = np.zeros(num_envs, dtype=np.int64)
        self.elapsed = np.zeros(num_envs, dtype=np.int64)
        self.horizon = model.horizon
        pairs = model.n_states * model.n_actions
        self._deterministic = model.max_outcomes == 1
        self._cumulative = model.cumulative.reshape(pairs, -1)
        self._next = model.next_state.reshape(pairs, -1)
        self._reward = model.reward.reshape(pairs, -1)
        self._terminal = model.terminal.reshape(pairs, -1)

    def reset(self, envs: np.ndarray) -> np.ndarray:
        states = self.sampler.reset(len(envs), self.rng)
        self.state[envs] = states
        self.elapsed[envs] = 0
        return states

    def step(
        self, envs: np.ndarray | None, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        sel: Any = slice(None) if envs is None else envs
        pair = self.state[sel] * self.n_actions + actions
        if self._deterministic:
            nxt = self._next[pair, 0]
            reward = self._reward[pair, 0]
            terminated = self._terminal[pair, 0]
        else:
            draws = self.rng.random(len(pair))
            # Outcome k is drawn when cumulative[k - 1] <= u < cumulative[k].
            outcome = (draws[:, None] >= self._cumulative[pair]).sum(axis=1)
            nxt = self._next[pair, outcome]
            reward = self._reward[pair, outcome]
            terminated = self._terminal[pair, outcome]
        self.state[sel] = nxt
        elapsed = self.elapsed[sel] + 1
        self.elapsed[sel] = elapsed
        if self.horizon is None:
            truncated = np.zeros(len(pair), dtype=bool)
        else:
            truncated = (elapsed >= self.horizon) & ~terminated
        return reward, nxt, terminated, truncated


class PlanSteps:
    """Episodes of a game the vector engine plays (its plan: game, limit, reward wrappers)."""

    def __init__(self, plan: Any, keyer: Any, num_envs: int, seed: Any = None) -> None:
        self.plan = plan
        self.keyer = keyer
        self.venv = plan.make_env(num_envs, seed)
        self.n_states = int(keyer.n_states)
        self.n_actions = int(self.venv.n_actions)

    def reset(self, envs: np.ndarray) -> np.ndarray:
        return np.asarray(self.keyer.keys(self.venv.reset(envs)), dtype=np.int64)

    def step(
        self, envs: np.ndarray | None, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        result = self.venv.step(actions, envs, autoreset=False)
        rewards = self.plan.transform_rewards(result.reward, result.info)
        keys = np.asarray(self.keyer.keys(result.next_obs), dtype=np.int64)
        return rewards, keys, result.terminated, result.truncated


def checkpoint_episodes(episodes: int, most: int = MAX_CHECKPOINTS) -> np.ndarray:
    """The episode counts (1-based, the last one `episodes`) at which greedy policies are valued."""
    count = max(1, min(episodes, most))
    points = np.rint(np.linspace(episodes / count, episodes, count)).astype(np.int64)
    # Rising already: drop repeats (np.unique would load numpy.ma on first use).
    return points[np.concatenate(([True], points[1:] != points[:-1]))]


def greedy_values(model: FiniteMDP, q: np.ndarray) -> np.ndarray:
    """The exact value (gamma 1) of the greedy policy of each table `q[m, S, A]`, ties split evenly.

    On a model whose every move has one outcome and with one start state, a
    policy that meets no tie on its way is valued along its path (all tables
    at once, in about log2(H) steps). The others, with an episode limit H,
    are valued at once: for a small model by powers of each policy's
    transition matrix (the sum of the first H steps' expected rewards in about
    log2(H) matrix products), else by H backward steps. With no limit, one
    at a time (minus infinity for a policy that may never end).
    """
    q = np.asarray(q, dtype=np.float64)
    tied = q == q.max(axis=2, keepdims=True)
    ties = tied.sum(axis=2)
    if model.horizon is not None and model.max_outcomes == 1 and len(q):
        starts = np.flatnonzero(model.initial)
        if starts.size == 1:
            values, walked = _path_values(model, tied, ties, int(starts[0]), model.horizon)
            rest = np.flatnonzero(~walked)
            if rest.size:
                values[rest] = _valued(model, tied[rest], ties[rest])
            return values
    return _valued(model, tied, ties)


def _path_values(
    model: FiniteMDP, tied: np.ndarray, ties: np.ndarray, start: int, horizon: int
) -> tuple[np.ndarray, np.ndarray]:
    """The rewards along each greedy policy's path from `start` over at most `horizon`
    moves, and which policies met no tie on the way (only their values are right).

    All paths at once by doubling: from every state, where 2**k moves lead, what
    they earn and whether they meet a tie, for k up to log2(horizon); a move that
    ends the episode leads to a sink that stays put and earns nothing.
    """
    m, n = ties.shape
    size = n + 1  # the states and the sink, per policy
    greedy = tied.argmax(axis=2)
    states = np.arange(n)
    lead = np.full((m, size), n, dtype=np.int64)
    earn = np.zeros((m, size))
    split = np.zeros((m, size), dtype=bool)
    ends = model.terminal[states, greedy, 0]
    lead[:, :n] = np.where(ends, n, model.next_state[states, greedy, 0])
    earn[:, :n] = model.reward[states, greedy, 0]
    split[:, :n] = ties > 1
    # Flat indices: policy i's states are i * size to (i + 1) * size - 1.
    first = np.arange(m, dtype=np.int64) * size
    lead = (lead + first[:, np.newaxis]).ravel()
    earn, split = earn.ravel(), split.ravel()
    at = first + start
    values = np.zeros(m)
    met = np.zeros(m, dtype=bool)
    remaining = horizon
    while remaining:
        if remaining & 1:
            values += earn[at]
            met |= split[at]
            at = lead[at]
        remaining >>= 1
        if remaining:
            earn = earn + earn[lead]
            split = split | split[lead]
            lead = lead[lead]
    return values, ~met


def _valued(model: FiniteMDP, tied: np.ndarray, ties: np.ndarray) -> np.ndarray:
    """`greedy_values` by the policies' matrices (see there), from their ties."""
    policy = tied / ties[..., np.newaxis]
    if model.horizon is None:
        return np.array([evaluate(model, p).value for p in policy])
    if model.n_states <= _DENSE_STATES:
        return _horizon_values_dense(model, policy, model.horizon)
    v = np.zeros((len(policy), model.n_states))
    reward, cont, nxt = model.expected_reward, model.continue_prob, model.next_state
    moving = np.arange(len(policy))  # tables whose values still change
    for _ in range(model.horizon):
        now = v[moving]
        after = (policy[moving] * (reward + (cont * now[:, nxt]).sum(axis=3))).sum(axis=2)
        changed = (after != now).any(axis=1)
        v[moving] = after
        # A table whose values did not change has reached its fixed point: every further
        # backward step gives the same values again.
        moving = moving[changed]
        if not moving.size:
            break
    return v @ model.initial


_DENSE_STATES = 256  # up to this many states, policies are valued by matrix powers


def _horizon_values_dense(model: FiniteMDP, policy: np.ndarray, horizon: int) -> np.ndarray:
    """Σ_{t<H} P^t r per policy, P its transition matrix over continuing outcomes."""
    n = model.n_states
    onto = np.zeros(model.next_state.shape + (n,))
    np.put_along_axis(onto, model.next_state[..., np.newaxis], 1.0, axis=3)
    step = np.einsum("sak,sakt->sat", model.continue_prob, onto)  # [S, A, S]
    matrix = np.einsum("msa,sat->mst", policy, step)  # [m, S, S]
    reward = (policy * model.expected_reward).sum(axis=2)  # [m, S]
    # Binary powers: `power` is P^n and `total` the sum of the first n steps for the bits
    # of H read so far, lowest first; n steps then m more: S_n + P^n S_m.
    total = np.zeros_like(reward)
    power_total = reward  # the sum of the first 2^k steps
    power = matrix  # P^(2^k)
    done_power = np.broadcast_to(np.eye(n), matrix.shape)  # P^(steps counted in total)
    remaining = horizon
    while remaining:
        if remaining & 1:
            total = total + np.einsum("mst,mt->ms", done_power, power_total)
            done_power = done_power @ power
        remaining >>= 1
        if remaining:
            power_total = power_total + np.einsum("mst,mt->ms", power, power_total)
            power = power @ power
    return total @ model.initial


@dataclass(frozen=True)
class SeedBatchState:
    """Where a batch stands: per seed, its episodes done, returns and exact values so far.

    `returns[i, e]` is seed i's online return of episode e + 1 (NaN until played; the
    columns stop at the furthest episode any seed has played);
    `exact[i, j]` its greedy policy's exact value at `checkpoints[j]` (NaN until
    reached; None without a model).
    """

    done: np.ndarray
    returns: np.ndarray
    checkpoints: np.ndarray
    exact: np.ndarray | None


class SeedBatch:
    """N seeds of one learner, E episodes each, as one batch (see the module docstring)."""

    def __init__(
        self,
        learner_class: type[Learner],
        hp: Settings,
        steps: BatchedSteps,
        seeds: int,
        episodes: int,
        *,
        seed: Any = None,
        model: FiniteMDP | None = None,
    ) -> None:
        if seeds < 1 or episodes < 1:
            raise ValueError("a batch needs at least one seed and one episode")
        self.steps = steps
        self.seeds = seeds
        self.episodes = episodes
        n_states = steps.n_states
        self.learner = learner_class(steps.n_actions, hp, n_states=seeds * n_states, seed=seed)
        self.offset = np.arange(seeds, dtype=np.int64) * n_states
        self.hp = hp
        # Each episode number's epsilon, worked out as the furthest seed gets there.
        self.epsilons = np.zeros(episodes)
        self._epsilons_known = 0
        first, last = hp.epsilon_at(0), hp.epsilon_at(episodes - 1)
        # The schedule is monotone: equal ends mean the same epsilon throughout.
        self._constant_epsilon = float(first) if first == last else None
        self.model = model if model is not None and model.n_states == n_states else None
        self.checkpoints = checkpoint_episodes(episodes)
        self.done = np.zeros(seeds, dtype=np.int64)
        self.returns = np.full((seeds, episodes), np.nan)
        self.exact = (
            None if self.model is None else np.full((seeds, len(self.checkpoints)), np.nan)
        )
        self._checkpoint_index = {int(c): j for j, c in enumerate(self.checkpoints)}
        self._to_value: list[tuple[int, int, np.ndarray]] = []  # (seed, checkpoint, its table)

    def state(self) -> SeedBatchState:
        """Copies of what the batch has so far (returns up to the furthest seed's episode)."""
        self._value_pending()
        return SeedBatchState(
            done=self.done.copy(),
            returns=self.returns[:, : int(self.done.max())].copy(),
            checkpoints=self.checkpoints.copy(),
            exact=None if self.exact is None else self.exact.copy(),
        )

    def _value_checkpoints(self, seeds: np.ndarray) -> None:
        """Keep a copy of the table of each of `seeds` that just reached a checkpoint."""
        if self.exact is None:
            return
        n_states = self.steps.n_states
        for i in seeds.tolist():
            j = self._checkpoint_index.get(int(self.done[i]))
            if j is not None:
                rows = slice(i * n_states, (i + 1) * n_states)
                self._to_value.append((i, j, self.learner.action_values(rows).copy()))
        if len(self._to_value) >= self.seeds:
            self._value_pending()

    def _value_pending(self) -> None:
        """Value the kept tables exactly, all at once."""
        if not self._to_value or self.exact is None or self.model is None:
            return
        values = greedy_values(self.model, np.stack([q for _, _, q in self._to_value]))
        for (i, j, _), value in zip(self._to_value, values, strict=True):
            self.exact[i, j] = value
        self._to_value = []

    def _update(self, batch: Transitions, eps: np.ndarray | float) -> None:
        learner = self.learner
        if isinstance(eps, float):
            learner.epsilon = eps
            learner.update(batch)
            return
        # Rows of different seeds touch different table rows, so updating them in groups
        # of one epsilon each is the same as one update with each row's own epsilon.
        values, groups = np.unique(eps, return_inverse=True)
        for g, value in enumerate(values.tolist()):
            learner.epsilon = value
            learner.update(_subset(batch, np.flatnonzero(groups == g)))

    def _act(self, rows: np.ndarray, eps: np.ndarray | float) -> np.ndarray:
        self.learner.epsilon = eps  # type: ignore[assignment]  # read per row by epsilon-greedy
        return self.learner.act_batch(rows)

    def _epsilons(self, active: np.ndarray) -> np.ndarray | float:
        """Each active seed's epsilon (that of its episode number), one float if all agree."""
        if self._constant_epsilon is not None:
            return self._constant_epsilon
        numbers = self.done[active]
        furthest = int(numbers.max())
        if furthest >= self._epsilons_known:
            stop = min(self.episodes, furthest + 256)
            for e in range(self._epsilons_known, stop):
                self.epsilons[e] = self.hp.epsilon_at(e)
            self._epsilons_known = stop
        eps = self.epsilons[numbers]
        first = float(eps[0])
        return first if (eps == first).all() else eps

    def _fast_tables(self) -> tuple[np.ndarray, np.ndarray] | None:
        """`fast_batch.fast_rule` for a game that is a deterministic `ModelSteps`."""
        steps = self.steps
        # A ModelSteps whose moves were replaced on the instance is played as it says.
        if type(steps) is not ModelSteps or "step" in vars(steps) or not steps._deterministic:
            return None
        return fast_rule(self.learner)

    def run(
        self,
        *,
        stop: Callable[[], bool] | None = None,
        report: Callable[[SeedBatch], None] | None = None,
        interval: float = 0.25,
        general: bool = False,
    ) -> bool:
        """Play until every seed has its episodes, or `stop()` says so; True when complete.

        `report(self)` is called about every `interval` seconds while it runs.
        Q-learning and SARSA on a deterministic model take `fast_batch.run_fast`,
        which gives the same numbers as the general loop below (`general` forces it).
        """
        if not general:
            tables = self._fast_tables()
            if tables is not None:
                return run_fast(self, tables, stop=stop, report=report, interval=interval,
                                check_every=_CHECK_EVERY)
        steps, learner, offset = self.steps, self.learner, self.offset
        sarsa_like = learner.needs_next_action
        n = self.seeds
        envs = np.arange(n, dtype=np.int64)
        keys = np.zeros(n, dtype=np.int64)
        pending = np.full(n, -1, dtype=np.int64)
        episode_return = np.zeros(n)
        active = envs[self.done < self.episodes]
        keys[active] = steps.reset(active)
        learner.forget_episodes(active)
        last_report = time.monotonic()
        count = 0
        while active.size:
            count += 1
            if count % _CHECK_EVERY == 0:
                if stop is not None and stop():
                    self._value_pending()
                    return False
                now = time.monotonic()
                if report is not None and now - last_report >= interval:
                    report(self)
                    last_report = now
            eps = self._epsilons(active)
            full = active.size == n
            sel: Any = slice(None) if full else active
            rows = offset[sel] + keys[sel]
            if sarsa_like:
                actions = pending[sel]
                fresh = np.flatnonzero(actions < 0)
                if fresh.size:
                    if full:
                        actions = actions.copy()  # a view of `pending` otherwise
                    actions[fresh] = self._act(
                        rows[fresh], eps if isinstance(eps, float) else eps[fresh]
                    )
            else:
                actions = self._act(rows, eps)
            rewards, next_keys, terminated, truncated = steps.step(None if full else active,
                                                                   actions)
            next_rows = offset[sel] + next_keys
            next_actions = self._act(next_rows, eps) if sarsa_like else None
            self._update(
                Transitions(rows, actions, rewards, next_rows, terminated, truncated,
                            next_actions, active),
                eps,
            )
            if next_actions is not None:
                pending[sel] = next_actions
            keys[sel] = next_keys
            episode_return[sel] += rewards
            finished = terminated | truncated
            if finished.any():
                ended = active[finished]
                self.returns[ended, self.done[ended]] = episode_return[ended]
                self.done[ended] += 1
                episode_return[ended] = 0.0
                self._value_checkpoints(ended)
                again = ended[self.done[ended] < self.episodes]
                if again.size:
                    keys[again] = steps.reset(again)
                    pending[again] = -1
                    learner.forget_episodes(again)
                if again.size < ended.size:
                    active = envs[self.done < self.episodes]
        self._value_pending()
        if report is not None:
            report(self)
        return True


def _subset(batch: Transitions, rows: np.ndarray) -> Transitions:
    return Transitions(
        batch.state[rows],
        batch.action[rows],
        batch.reward[rows],
        batch.next_state[rows],
        batch.terminated[rows],
        batch.truncated[rows],
        None if batch.next_action is None else batch.next_action[rows],
        None if batch.env is None else batch.env[rows],
    )
