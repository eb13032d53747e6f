"""The vector engine: any learner on many envs at once, beside the scalar `Trainer`.

`VectorTrainer` is an `Engine`, as the scalar `Trainer` is: it trains the
same learner (any `tui_gym.algorithms.Learner` with a dense table: its
tables, episode count and epsilon schedule) but plays `num_envs` games side
by side on the batched env the game's `BatchedForm` makes, so every numpy
call serves hundreds of steps. Build it from an env built by the wrapper
catalog and the game's form:

    trainer = VectorTrainer(env, learner, keyer, form=game.batched_form(kwargs), seed=0)
    trainer.run(episodes=200_000)

or with `make_vector_trainer(env_id, env_kwargs, choices, learner, keyer, form=...)`.
`plan_for_env` reads the env's wrappers; an env with no batched form raises
`NoBatchedForm`.

One batch step, top to bottom, following the learner protocol
(`tui_gym.algorithms.base`); the env with index i is the learner's env
`1 + i`:

1. Envs without an episode start one, each numbered in the order episodes
   start; the learner forgets anything it kept of an earlier episode there.
   When the episode quota of `run(episodes=...)` is smaller than the number
   of games in progress, only the oldest episodes step (so a run finishes
   exactly that many).
2. Actions for every stepping env: `act_batch`, or for a learner that picks
   its next action before its update (SARSA) the action picked at the
   previous step (`act_batch` only where an episode just started).
3. One batched env step; the wrappers' reward transforms; keys of the next
   observations; for SARSA, the next actions.
4. The learner's batched `update`.
5. `end_episodes` for the finished episodes (epsilon is thus updated once
   per batch). Their statistics go into the rolling windows and curves in
   the order the episodes *started*: a result waits until every episode
   that started before it has finished. Many games started at once finish
   shortest first, so recording them as they finish would begin every
   curve on the shortest episodes (a biased sample); in start order every
   stretch of a curve is an unbiased sample of the episodes of its time.
   What waits is bounded by the games in progress times the longest
   episode.

Episodes in progress survive between `run` calls, and `seconds` and `stop`
end a call only between batch steps, so cutting a run into time slices does
not change it: with the same seeds (the trainer's for the envs, the
learner's for exploration), one `run(episodes=n)` and any number of
`run(episodes=n - done, seconds=...)` calls give the same table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import Learner, Transitions
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.stats import EpisodeStats
from tui_gym.core.training import EPISODE_RETURNS, SERIES_NAMES, Engine
from tui_gym.core.vector.base import BatchedForm
from tui_gym.core.vector.plan import VectorPlan, plan_for_env
from tui_gym.core.wrappers import WrapperChoice, build_env_lenient

__all__ = ["DEFAULT_NUM_ENVS", "VectorTrainer", "make_vector_trainer"]

# Episodes/s grow with num_envs and level off by a few thousand, while learning per
# episode is the same for all of them: 2048 is most of the speed with batch steps of
# about a millisecond.
DEFAULT_NUM_ENVS = 2048
MIN_NUM_ENVS = 256  # fewer games at once than this leave numpy too little to do a step


class VectorTrainer(Engine):
    """Trains a learner on `num_envs` copies of an env at once (see the module docstring).

    Args:
        env: an env built by the wrapper catalog (`build_env`); its wrappers
            are read with `plan_for_env` and played in batches (the env itself
            is never stepped).
        agent: the dense-table learner to train (shared, as with `Trainer`).
        keyer: the keyer of `env`'s observation space.
        form: the game's batched form (None or `NotAvailable`: there is none,
            and `NoBatchedForm` says so).
        made_limit: the limit `gym.make` put on the game (by default the
            registry's), for `plan.describe`.
        seed: seeds the batched env; the learner's own seed drives exploration.
        num_envs: games played side by side (None: the form's choice, else
            `DEFAULT_NUM_ENVS`, and at most a tenth of the episode budget, so
            that a short run still plays each game through many episodes).
        window, series_capacity, publish_interval: as for `Trainer`.
    """

    engine = "vector"

    def __init__(
        self,
        env: gym.Env,
        agent: Learner,
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
        self._env_ids = np.arange(1, n + 1, dtype=np.int64)  # the learner's env ids
        self._pending = np.full(n, -1, dtype=np.int64)  # SARSA's next actions; -1: none yet
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

    # --- the Engine surface ----------------------------------------------
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
        self._pending[idle] = -1
        self.agent.forget_episodes(self._env_ids[idle])
        self._n_live += len(idle)
        self._returns[idle] = 0.0
        self._lengths[idle] = 0
        self._abs_td[idle] = 0.0

    def _choose(self, keys: np.ndarray, sel: Any) -> np.ndarray:
        """The actions of the stepping envs (see the module docstring, step 2)."""
        agent = self.agent
        if not agent.needs_next_action:
            return agent.act_batch(keys)
        actions = self._pending[sel]
        if isinstance(sel, slice):  # a view of the whole array, not a copy
            actions = actions.copy()
        fresh = np.flatnonzero(actions < 0)
        if fresh.size:
            actions[fresh] = agent.act_batch(keys[fresh])
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
                # Start numbers are distinct: the quota-th smallest one splits them in O(n),
                # and `index` stays in env order.
                seqs = self._start_seq[index]
                index = index[seqs <= np.partition(seqs, quota - 1)[quota - 1]]
        sel: Any = slice(None) if index is None else index

        agent = self.agent
        keys = self._keys[sel]
        actions = self._choose(keys, sel)
        result = self.venv.step(actions, index, autoreset=False)
        rewards = self.plan.transform_rewards(result.reward, result.info)
        next_keys = self.keyer.keys(result.next_obs)
        next_actions = agent.act_batch(next_keys) if agent.needs_next_action else None
        td = agent.update(Transitions(
            keys, actions, rewards, next_keys, result.terminated, result.truncated,
            next_actions, self._env_ids[sel],
        ))
        if next_actions is not None:
            self._pending[sel] = next_actions
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
        move the learner's schedule on."""
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
        self.agent.end_episodes(count)
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
        self.series[EPISODE_RETURNS].push_many(rows[:, 0])
        ret, length, td, eps = rows[-1].tolist()
        self.last = EpisodeStats(ret, int(length), td, eps)


def _ring_size(at_least: int) -> int:
    """The smallest power of two that is at least `at_least` (and at least 2)."""
    return 1 << max(1, (at_least - 1).bit_length())


def make_vector_trainer(
    env_id: str,
    env_kwargs: Mapping[str, Any] | None,
    choices: Sequence[WrapperChoice],
    agent: Learner,
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
