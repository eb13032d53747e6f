"""The vector engine: Q-learning on many envs at once, a drop-in for `Trainer`.

`VectorTrainer` trains the same `QAgent` the scalar `Trainer` does (its
table, update counts, episode count and epsilon schedule) but plays
`num_envs` games side by side on the batched env the game's `BatchedForm`
makes, so every numpy call serves hundreds of steps. Build it like a
`Trainer`, from an env built by the wrapper catalog and the game's form:

    trainer = VectorTrainer(env, agent, keyer, form=game.batched_form(kwargs), seed=0)
    trainer.run(episodes=200_000)

or with `make_vector_trainer(env_id, env_kwargs, choices, agent, keyer, form=...)`.
`plan_for_env` reads the env's wrappers; an env with no batched form raises
`NoBatchedForm`.

One batch step, top to bottom:

1. Envs without an episode start one, each numbered in the order episodes
   start. When the episode quota of `run(episodes=...)` is smaller than the
   number of games in progress, only the oldest episodes step (so a run
   finishes exactly that many).
2. Epsilon-greedy actions for every stepping env: a random action with
   probability `agent.epsilon`, else the best-valued one, ties broken
   uniformly at random (the highest of independent uniform draws among the
   tied actions wins).
3. One batched env step; the wrappers' reward transforms; keys of the next
   observations.
4. The batched Q-learning update (`batched_q_update`).
5. The agent's episode count and epsilon move on for the finished episodes
   (epsilon is thus updated once per batch). Their statistics go into the
   rolling windows and curves in the order the episodes *started*: a result
   waits until every episode that started before it has finished. Many games
   started at once finish shortest first, so recording them as they finish
   would begin every curve on the shortest episodes (a biased sample); in
   start order every stretch of a curve is an unbiased sample of the episodes
   of its time. What waits is bounded by the games in progress times the
   longest episode.

Episodes in progress survive between `run` calls, and `seconds` and `stop`
end a call only between batch steps, so cutting a run into time slices does
not change it: with the same seeds (the trainer's for the envs, the agent's
for exploration), one `run(episodes=n)` and any number of
`run(episodes=n - done, seconds=...)` calls give the same Q-table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.core.agent import QAgent
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.stats import EpisodeStats
from tui_gym.core.training import SERIES_NAMES, StepEvent, Trainer
from tui_gym.core.vector.base import BatchedForm
from tui_gym.core.vector.plan import VectorPlan, plan_for_env
from tui_gym.core.wrappers import WrapperChoice, build_env_lenient

__all__ = ["DEFAULT_NUM_ENVS", "VectorTrainer", "batched_q_update", "make_vector_trainer"]

# Episodes/s grow with num_envs and level off by a few thousand, while learning per
# episode is the same for all of them: 2048 is most of the speed with batch steps of
# about a millisecond.
DEFAULT_NUM_ENVS = 2048
MIN_NUM_ENVS = 256  # fewer games at once than this leave numpy too little to do a step

# 1 - lr is floored here before taking logs: a step size of 1 wipes out what came before.
_TINY = 1e-300


def batched_q_update(
    agent: QAgent,
    keys: np.ndarray,
    actions: np.ndarray,
    rewards: np.ndarray,
    terminated: np.ndarray,
    next_keys: np.ndarray,
) -> np.ndarray:
    """Q-learning updates for a batch of transitions; returns each TD error.

    Targets `r + discount * max_a' Q(s', a')` (0 after termination) are all
    read from the table as it is before the batch. Transitions that share a
    (state, action) are then applied one after the other, in batch order,
    each with its own step size (`max(lr, 1/n)` for the "visits" schedule,
    n counting this update), exactly as `QAgent.update` would apply them if
    the targets stayed fixed. This is done in closed form: after updates
    1..m with step sizes a_i, Q = prod(1 - a_i) Q_0 + sum_i a_i prod_{j>i}(1 - a_j) t_i,
    the products taken as sums of logs within each group of a sorted batch.
    So a batch is sequential Q-learning whose bootstrap values lag by at
    most one batch. The TD errors returned (for the |TD| statistic) are
    measured against the table before the batch.

    `keys` and `next_keys` are dense row numbers of `agent.q`; the agent's
    `counts` and `visits` grow by one per transition.
    """
    hp = agent.hp
    n_actions = agent.n_actions
    if not (agent.q.flags.c_contiguous and agent.counts.flags.c_contiguous):
        agent.q = np.ascontiguousarray(agent.q)  # so the flat views below write through
        agent.counts = np.ascontiguousarray(agent.counts)
    q_flat = agent.q.reshape(-1)
    counts_flat = agent.counts.reshape(-1)
    future = agent.q[next_keys].max(axis=1)
    future[terminated] = 0.0
    targets = rewards + hp.discount * future
    flat = keys * n_actions + actions
    td = targets - q_flat[flat]
    if len(flat) == 0:
        return td

    # A stable sort of small integers is a radix sort in numpy: several times faster.
    sortable = flat.astype(np.uint16) if q_flat.size <= 1 << 16 else flat
    order = np.argsort(sortable, kind="stable")
    cells = flat[order]
    goals = targets[order]
    m = len(cells)
    first = np.ones(m, dtype=bool)
    first[1:] = cells[1:] != cells[:-1]
    starts = np.flatnonzero(first)
    group = np.cumsum(first) - 1
    sizes = np.diff(np.append(starts, m))
    if hp.learning_rate_schedule == "visits":
        rank = np.arange(1, m + 1) - starts[group]
        alpha = np.maximum(hp.learning_rate, 1.0 / (counts_flat[cells] + rank))
    else:
        alpha = np.full(m, hp.learning_rate)
    log_keep = np.log(np.maximum(1.0 - alpha, _TINY))
    running = np.cumsum(log_keep)
    ends = starts + sizes - 1
    weights = alpha * np.exp(running[ends][group] - running)
    keep_all = np.exp(running[ends] - running[starts] + log_keep[starts])
    unique = cells[starts]
    q_flat[unique] = keep_all * q_flat[unique] + np.add.reduceat(weights * goals, starts)
    counts_flat[unique] += sizes
    np.add.at(agent.visits, unique // n_actions, sizes)
    return td


class VectorTrainer(Trainer):
    """Runs Q-learning on `num_envs` copies of an env at once; the `Trainer` API.

    Args:
        env: an env built by the wrapper catalog (`build_env`); its wrappers
            are read with `plan_for_env` and played in batches (the env itself
            is never stepped).
        agent: the dense-table `QAgent` to train (shared, as with `Trainer`).
        keyer: the keyer of `env`'s observation space.
        form: the game's batched form (None or `NotAvailable`: there is none,
            and `NoBatchedForm` says so).
        made_limit: the limit `gym.make` put on the game (by default the
            registry's), for `plan.describe`.
        seed: seeds the batched env; the agent's own seed drives exploration.
        num_envs: games played side by side (None: the form's choice, else
            `DEFAULT_NUM_ENVS`, and at most a tenth of the episode budget, so
            that a short run still plays each game through many episodes).
        window, series_capacity, publish_interval: as for `Trainer`.
    """

    engine = "vector"

    def __init__(
        self,
        env: gym.Env,
        agent: QAgent,
        keyer: ObservationKeyer,
        *,
        form: BatchedForm | NotAvailable | None,
        made_limit: int | None | str = "registry",
        seed: int | None = None,
        num_envs: int | None = None,
        window: int = 1000,
        series_capacity: int = 256,
        publish_interval: float = 0.1,
    ) -> None:
        self.plan: VectorPlan = plan_for_env(env, form, made_limit)
        if not (keyer.dense and agent.dense):
            raise ValueError("the vector engine needs a dense observation keyer and Q-table")
        n_actions = getattr(env.action_space, "n", None)
        if keyer.n_states != agent.n_states or agent.n_actions != n_actions:
            raise ValueError("the agent's table does not match the env's states and actions")
        if keyer.signature != repr(env.observation_space):
            raise ValueError("the keyer was not built from this env's observation space")
        if num_envs is None:
            widest = self.plan.form.num_envs or DEFAULT_NUM_ENVS
            num_envs = min(widest, max(MIN_NUM_ENVS, agent.hp.episodes // 10))
        self.venv = self.plan.make_env(num_envs, seed)
        self.num_envs = self.venv.num_envs
        n = self.num_envs
        self._live = np.zeros(n, dtype=bool)  # has an episode in progress
        self._n_live = 0
        self._keys = np.zeros(n, dtype=np.int64)
        self._returns = np.zeros(n, dtype=np.float64)
        self._lengths = np.zeros(n, dtype=np.int64)
        self._abs_td = np.zeros(n, dtype=np.float64)
        # Episode results held until every earlier-started episode has finished: a ring
        # indexed by start number, `_released` the first start number not yet recorded.
        self._start_seq = np.zeros(n, dtype=np.int64)  # start number of each env's episode
        # The exploration rate each env's episode started with: what its curve point shows,
        # so that points in start order follow the schedule.
        self._start_epsilon = np.zeros(n, dtype=np.float64)
        self._next_seq = 0
        self._released = 0
        self._held = np.zeros((_ring_size(2 * n), len(SERIES_NAMES)), dtype=np.float64)
        self._last_finished: EpisodeStats | None = None
        super().__init__(
            env,
            agent,
            keyer,
            seed=seed,
            window=window,
            series_capacity=series_capacity,
            publish_interval=publish_interval,
        )

    # --- the Trainer surface ---------------------------------------------
    def step(self) -> StepEvent:
        """Not available: the vector engine moves many envs at once (animate with `Trainer`)."""
        raise NotImplementedError(
            "the vector engine steps many envs at once; use the scalar Trainer to animate moves"
        )

    def run_episode(self) -> EpisodeStats:
        """Finish one more episode (the oldest in progress; the others wait) and
        return its statistics."""
        self.run(episodes=1)
        assert self._last_finished is not None
        return self._last_finished

    @property
    def held(self) -> int:
        """Finished episodes whose statistics wait for an earlier-started one to finish."""
        return self.episodes_started - self._released - self._n_live

    @property
    def episodes_started(self) -> int:
        return self._next_seq

    def episode_in_progress(self) -> bool:
        return self._n_live > 0

    def current_observation(self) -> Any:
        return None  # many games are in progress, none of them "the" current one

    # --- one batch step --------------------------------------------------
    def _start_episodes(self) -> None:
        """Start an episode in every idle env.

        Every env always has an episode in progress (a steady state): near the
        end of a quota only some envs step, and the rest carry their episodes
        over to the next call. Waiting instead for the last in-progress
        episodes to finish would end every run on its longest episodes and
        skew the rolling statistics.
        """
        if self._n_live == self.num_envs:
            return
        idle = np.flatnonzero(~self._live)
        self._keys[idle] = self.keyer.keys(self.venv.reset(idle))
        self._number(idle)
        self._live[idle] = True
        self._n_live += len(idle)
        self._returns[idle] = 0.0
        self._lengths[idle] = 0
        self._abs_td[idle] = 0.0

    def _choose(self, keys: np.ndarray) -> np.ndarray:
        """Epsilon-greedy actions, ties among the best broken uniformly at random.

        Which envs explore is drawn first, and the greedy choice is made only for
        the others (early in a run nearly every env explores).
        """
        agent = self.agent
        rng = agent.rng
        k, n_actions = len(keys), agent.n_actions
        explore = rng.random(k) < agent.epsilon
        actions = np.empty(k, dtype=np.int64)
        count = int(np.count_nonzero(explore))
        if count:
            actions[explore] = rng.integers(n_actions, size=count)
        if count < k:
            values = agent.q[keys[~explore]]
            tied = values == values.max(axis=1, keepdims=True)
            draws = rng.random(values.shape)
            actions[~explore] = np.argmax(np.where(tied, draws, -1.0), axis=1)
        return actions

    def _advance(self, limit: int | None) -> int:
        return self._batch(limit)

    def _batch(self, quota: int | None) -> int:
        """One batched step of every stepping env; returns the episodes it finished."""
        self._start_episodes()
        if self._n_live == 0:
            return 0
        index: np.ndarray | None = None
        if self._n_live < self.num_envs or (quota is not None and quota < self.num_envs):
            index = np.flatnonzero(self._live)
            if quota is not None and quota < len(index):
                # The oldest episodes step and the others wait, so no more than the quota
                # finish, and what finishes is what the statistics wait for.
                oldest = np.argsort(self._start_seq[index], kind="stable")[:quota]
                index = np.sort(index[oldest])
        sel: Any = slice(None) if index is None else index

        keys = self._keys[sel]
        actions = self._choose(keys)
        result = self.venv.step(actions, index, autoreset=False)
        rewards = self.plan.transform_rewards(result.reward, result.info)
        next_keys = self.keyer.keys(result.next_obs)
        td = batched_q_update(self.agent, keys, actions, rewards, result.terminated, next_keys)
        self.steps += len(keys)
        self._keys[sel] = next_keys
        self._returns[sel] += rewards
        self._lengths[sel] += 1
        self._abs_td[sel] += np.abs(td)

        finished = np.flatnonzero(result.terminated | result.truncated)
        if finished.size == 0:
            return 0
        envs = finished if index is None else index[finished]
        self._live[envs] = False
        self._n_live -= len(envs)
        self._record(envs)
        return len(envs)

    def _number(self, envs: np.ndarray) -> None:
        """Give the episodes starting in `envs` the next start numbers."""
        first = self._next_seq
        self._next_seq += len(envs)
        while self._next_seq - self._released > len(self._held):
            self._grow()
        self._start_seq[envs] = np.arange(first, self._next_seq)
        self._start_epsilon[envs] = self.agent.epsilon

    def _grow(self) -> None:
        """Double the ring of held results, keeping each at its start number's place."""
        old = self._held
        seqs = np.arange(self._released, self._next_seq)
        self._held = np.zeros((2 * len(old), old.shape[1]), dtype=np.float64)
        self._held[seqs % len(self._held)] = old[seqs % len(old)]

    def _record(self, envs: np.ndarray) -> None:
        """Hold finished episodes' statistics, release those whose turn has come, and
        move the agent's schedule on."""
        lengths = self._lengths[envs].astype(np.float64)
        columns = np.column_stack([
            self._returns[envs],
            lengths,
            self._abs_td[envs] / np.maximum(lengths, 1.0),
            self._start_epsilon[envs],
        ])
        self._held[self._start_seq[envs] % len(self._held)] = columns
        ret, length, td, eps = columns[-1].tolist()
        self._last_finished = EpisodeStats(ret, int(length), td, eps)
        count = len(envs)
        self.episodes += count
        agent = self.agent
        agent.episode += count
        agent.epsilon = agent.hp.epsilon_at(agent.episode)
        self._release()

    def _release(self) -> None:
        """Record, in start order, every held result with no earlier episode in progress."""
        live = self._start_seq[self._live]
        frontier = int(live.min()) if live.size else self._next_seq
        if frontier <= self._released:
            return
        rows = self._held[np.arange(self._released, frontier) % len(self._held)]
        self._released = frontier
        for name, values in zip(SERIES_NAMES, rows.T, strict=True):
            means = self.windows[name].push_many(values)
            self.series[name].push_many(means)
        ret, length, td, eps = rows[-1].tolist()
        self.last = EpisodeStats(ret, int(length), td, eps)


def _ring_size(at_least: int) -> int:
    """The smallest power of two that is at least `at_least` (and at least 2)."""
    return 1 << max(1, (at_least - 1).bit_length())


def make_vector_trainer(
    env_id: str,
    env_kwargs: Mapping[str, Any] | None,
    choices: Sequence[WrapperChoice],
    agent: QAgent,
    keyer: ObservationKeyer | None = None,
    *,
    form: BatchedForm | NotAvailable | None,
    seed: int | None = None,
    num_envs: int | None = None,
    **options: Any,
) -> VectorTrainer:
    """A `VectorTrainer` for a game and wrapper choice, built as a `Session` builds its env.

    Choices that do not fit are skipped, as `build_env_lenient` skips them.
    `keyer` defaults to one for the built env; `form` is the game's batched
    form. `options` go to `VectorTrainer` (`window`, `series_capacity`,
    `publish_interval`). Raises `NoBatchedForm` when the game or a wrapper has
    no batched form.
    """
    env, _ = build_env_lenient(env_id, env_kwargs, choices)
    if keyer is None:
        keyer = ObservationKeyer(env.observation_space)
    return VectorTrainer(env, agent, keyer, form=form, seed=seed, num_envs=num_envs, **options)
