"""The engines' shared loop, and the scalar engine: episodes in chunks, with bounded statistics.

`Engine` is what every engine shares: the learner it trains (any
`tui_gym.algorithms.Learner`), `run(episodes=…)` / `run(seconds=…)` in
chunks so a front end can interleave drawing, pausing and changing
settings, per-episode return, length, mean |TD error| and epsilon in
`RollingWindow`s and whole-run `Series` (memory is fixed however long it
runs), and `snapshot()`, an immutable `TrainingSnapshot` (numpy copies) for
viewers on other threads; `latest` holds the most recent one. Each engine
writes `_advance`, its small piece of work.

`Trainer` is the scalar engine: one Gymnasium env, any wrapper, one move at
a time (`step()` animates, and can explain the update it made). It drives
the learner through the protocol of `tui_gym.algorithms.base`. The vector
engine (`tui_gym.core.vector.VectorTrainer`) is another `Engine`.
`continue_run` decides how new hyperparameters apply to a run under way.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import SCALAR_ENV, Learner, Settings, UpdateRecord
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.stats import EpisodeStats, RollingWindow, Series

SERIES_NAMES = ("return", "length", "td_error", "epsilon")
# The series of each episode's own return (bucket means, not rolling means): what the run
# history records as a run's `return` curve.
EPISODE_RETURNS = "episode_return"
ADVANCE_STEPS = 256  # steps after which `Trainer.run` checks the clock and its stop flag


class StopFlag(Protocol):
    """What `Trainer.run` checks between pieces of work (a `threading.Event` will do)."""

    def is_set(self) -> bool: ...


@dataclass(frozen=True)
class TrainingSnapshot:
    """What a viewer needs to draw one frame of training; never changes."""

    engine: str
    episodes: int
    steps: int
    seconds: float  # time spent training
    episodes_per_second: float  # recent rate
    epsilon: float
    mean_return: float  # over the rolling window
    mean_length: float
    mean_abs_td: float
    window: int
    series: dict[str, tuple[float, ...]]  # whole-run history per quantity
    q: np.ndarray  # copy of the learner's action values (rows used)
    keys: list[Hashable] | None  # the key of each row for sparse tables, None when dense
    budget: int  # the episode budget from the hyperparameters
    last: EpisodeStats | None = None
    version: int = 0  # increases with every snapshot of a run
    recorded: int = 0  # episodes in the statistics (fewer than `episodes` after a load)
    _lookup: dict[Hashable, int] | None = field(default=None, repr=False, compare=False)

    def values(self, keys: list[Hashable]) -> np.ndarray:
        """Action values for the given keys (zeros for unseen states), like `Learner.values`."""
        out = np.zeros((len(keys), self.q.shape[1]))
        if self.keys is None:
            if keys:
                out[:] = self.q[np.asarray(keys, dtype=np.int64)]
            return out
        lookup = self._lookup
        if lookup is None:
            lookup = {k: i for i, k in enumerate(self.keys)}
            object.__setattr__(self, "_lookup", lookup)
        for i, key in enumerate(keys):
            row = lookup.get(key)
            if row is not None:
                out[i] = self.q[row]
        return out

    @property
    def progress(self) -> float:
        return min(1.0, self.episodes / self.budget) if self.budget else 0.0


@dataclass(frozen=True)
class TrainerProgress:
    """A trainer's counts and bounded statistics, to hand to another trainer."""

    episodes: int
    steps: int
    seconds: float
    windows: dict[str, RollingWindow]
    series: dict[str, Series]
    last: EpisodeStats | None
    rate_mark: tuple[float, int]
    rate: float
    version: int


@dataclass(frozen=True)
class StepEvent:
    """One move of the agent, for animated training."""

    observation: Any
    action: int
    reward: float
    next_observation: Any
    terminated: bool
    truncated: bool
    episode_done: EpisodeStats | None
    episode: int = 0  # the 1-based number of the episode this step belongs to
    step: int = 0  # the 1-based number of this step within its episode
    last_update: UpdateRecord | None = None  # how the learner used it, when asked to explain


class Engine(ABC):
    """What every engine shares: a learner, chunked runs, statistics and snapshots.

    `agent` is the learner being trained (shared with the session and any
    other engine of it). A subclass writes `_advance`, one small piece of
    work, and may finish `episodes` in any order it likes.
    """

    engine = ""

    def __init__(
        self,
        env: gym.Env,
        agent: Learner,
        keyer: ObservationKeyer,
        *,
        seed: int | None = None,
        window: int = 1000,
        series_capacity: int = 256,
        publish_interval: float = 0.1,
    ) -> None:
        self.env = env
        self.agent = agent
        self.keyer = keyer
        self.seed = seed
        self.publish_interval = publish_interval
        self.episodes = 0
        self.steps = 0
        self.seconds = 0.0
        self.windows = {name: RollingWindow(window) for name in SERIES_NAMES}
        self.series = {name: Series(series_capacity) for name in (*SERIES_NAMES, EPISODE_RETURNS)}
        self.last: EpisodeStats | None = None
        self._rate_mark = (0.0, 0)  # (seconds, episodes) at the last rate sample
        self._rate = 0.0
        self._version = 0
        self.latest: TrainingSnapshot = self.snapshot()

    @abstractmethod
    def _advance(self, limit: int | None) -> int:
        """A small piece of work (milliseconds) finishing at most `limit` episodes;
        returns how many it finished."""

    @abstractmethod
    def run_episode(self) -> EpisodeStats:
        """Finish one more episode and return its statistics."""

    @abstractmethod
    def episode_in_progress(self) -> bool:
        """Whether an episode has started and not ended."""

    def current_observation(self) -> Any:
        """The observation the agent is about to act on (None when there is no one)."""
        return None

    def _record_episode(self, stats: EpisodeStats) -> None:
        """Count one finished episode into the windows and curves."""
        self.last = stats
        windows, series = self.windows, self.series
        for name, value in zip(
            SERIES_NAMES,
            (stats.episode_return, stats.length, stats.mean_abs_td, stats.epsilon),
            strict=True,
        ):
            window = windows[name]
            window.push(value)
            series[name].push(window.mean)
        series[EPISODE_RETURNS].push(stats.episode_return)

    # --- chunks ----------------------------------------------------------
    def run(
        self,
        episodes: int | None = None,
        seconds: float | None = None,
        stop: StopFlag | None = None,
        on_publish: Callable[[TrainingSnapshot], None] | None = None,
    ) -> int:
        """Run until `episodes` more episodes, `seconds` elapse, or `stop` is set.

        Exactly `episodes` finish when that limit is what stops the run;
        `seconds` and `stop` are checked between small pieces of work (see
        `_advance`). Returns the number of episodes finished, and publishes a
        snapshot to `latest` (and `on_publish`) every `publish_interval`
        seconds and at the end.
        """
        if episodes is None and seconds is None and stop is None:
            raise ValueError("run() needs episodes, seconds or a stop event")
        start = began = time.perf_counter()
        next_publish = start + self.publish_interval
        done = 0
        while episodes is None or done < episodes:
            done += self._advance(None if episodes is None else episodes - done)
            now = time.perf_counter()
            if seconds is not None and now - began >= seconds:
                break
            if stop is not None and stop.is_set():
                break
            if now >= next_publish:
                self.seconds += now - start
                start = now
                self.publish(on_publish)
                next_publish = now + self.publish_interval
        self.seconds += time.perf_counter() - start
        self.publish(on_publish)
        return done

    def publish(self, callback: Callable[[TrainingSnapshot], None] | None = None) -> None:
        snap = self.snapshot()
        self.latest = snap
        if callback is not None:
            callback(snap)

    def _update_rate(self) -> float:
        t0, e0 = self._rate_mark
        dt = self.seconds - t0
        if dt >= 0.5:
            self._rate = (self.episodes - e0) / dt
            self._rate_mark = (self.seconds, self.episodes)
        elif self._rate == 0.0 and dt > 0:
            return (self.episodes - e0) / dt
        return self._rate

    def snapshot(self) -> TrainingSnapshot:
        """An immutable copy of the current statistics and the learner's action values."""
        q, keys = self.agent.table()
        self._version += 1
        w = self.windows
        return TrainingSnapshot(
            engine=self.engine,
            episodes=self.episodes,
            steps=self.steps,
            seconds=self.seconds,
            episodes_per_second=self._update_rate(),
            epsilon=self.agent.epsilon,
            mean_return=w["return"].mean,
            mean_length=w["length"].mean,
            mean_abs_td=w["td_error"].mean,
            window=w["return"].size,
            series={name: s.points() for name, s in self.series.items()},
            q=q,
            keys=keys,
            budget=self.agent.hp.episodes,
            last=self.last,
            version=self._version,
            recorded=w["return"].count,
        )

    def progress(self) -> TrainerProgress:
        """Counts and statistics so far (to carry on elsewhere)."""
        return TrainerProgress(
            self.episodes, self.steps, self.seconds, self.windows, self.series, self.last,
            self._rate_mark, self._rate, self._version,
        )

    def restore(self, progress: TrainerProgress) -> None:
        """Carry on from `progress` (this trainer's agent is the one that made it)."""
        self.episodes, self.steps = progress.episodes, progress.steps
        self.seconds, self.windows = progress.seconds, progress.windows
        self.series, self.last = progress.series, progress.last
        self._rate_mark, self._rate = progress.rate_mark, progress.rate
        self._version = progress.version
        self.publish()

    def adopt_progress(self, other: Engine) -> None:
        """Carry on another engine's counts and statistics (the agent is shared)."""
        self.restore(other.progress())

    @property
    def remaining(self) -> int:
        return max(0, self.agent.hp.episodes - self.episodes)


class Trainer(Engine):
    """The scalar engine: one env, a step, an episode or a chunk at a time.

    Each step follows the learner protocol with a batch of one: the action
    (`act`, or for SARSA the next action chosen at the previous step), the
    env step, the next action first when the learner needs it, then
    `update_one`, and `end_episodes(1)` when the episode ends.
    """

    engine = "scalar"

    def __init__(self, env: gym.Env, agent: Learner, keyer: ObservationKeyer, **options: Any):
        self._obs: Any = None
        self._key: Hashable | None = None
        self._next_action: int | None = None  # chosen in advance (SARSA), taken next step
        self._ep_return = 0.0
        self._ep_len = 0
        self._ep_td = 0.0
        self._env_seeded = False  # the env's first reset here takes the seed
        super().__init__(env, agent, keyer, **options)

    # --- one move --------------------------------------------------------
    def _begin_episode(self) -> None:
        if not self._env_seeded and self.seed is not None:
            # Also when this engine takes over a run another began (the vector engine
            # before an animated step): its episodes are not 0 then, and an env never
            # seeded would draw its first placement from the operating system.
            obs, _ = self.env.reset(seed=self.seed)
            self._env_seeded = True
        else:
            obs, _ = self.env.reset()
        # Whatever the learner kept of an episode this engine no longer plays goes.
        self.agent.forget_episodes((SCALAR_ENV,))
        self._obs = obs
        self._key = self.keyer.key(obs)
        self._next_action = None
        self._ep_return = 0.0
        self._ep_len = 0
        self._ep_td = 0.0

    def step(self, explain: bool = False) -> StepEvent:
        """Take one environment step (starting an episode if none is running).

        With `explain` the event carries the learner's record of the update.
        """
        if self._obs is None:
            self._begin_episode()
        obs, key = self._obs, self._key
        agent = self.agent
        action = self._next_action
        if action is None:
            action = agent.act(key)
        next_obs, reward, terminated, truncated, _ = self.env.step(action)
        next_key = self.keyer.key(next_obs)
        next_action = agent.act(next_key) if agent.needs_next_action else None
        td = agent.update_one(key, action, float(reward), next_key, bool(terminated),
                              bool(truncated), next_action)
        record = agent.last_update if explain else None
        self.steps += 1
        self._ep_return += float(reward)
        self._ep_len += 1
        self._ep_td += abs(td)
        episode, step = self.episodes + 1, self._ep_len
        done_stats = None
        if terminated or truncated:
            done_stats = self._finish_episode()
        else:
            self._obs, self._key, self._next_action = next_obs, next_key, next_action
        return StepEvent(obs, action, float(reward), next_obs, bool(terminated),
                         bool(truncated), done_stats, episode, step, record)

    def _finish_episode(self) -> EpisodeStats:
        stats = EpisodeStats(
            episode_return=self._ep_return,
            length=self._ep_len,
            mean_abs_td=self._ep_td / max(1, self._ep_len),
            epsilon=self.agent.epsilon,
        )
        self.agent.end_episodes(1)
        self.episodes += 1
        self._record_episode(stats)
        self._obs = None
        self._next_action = None
        return stats

    def run_episode(self) -> EpisodeStats:
        """Play one whole episode (finishing the one in progress, if any)."""
        while True:
            event = self.step()
            if event.episode_done is not None:
                return event.episode_done

    def _advance(self, limit: int | None) -> int:
        """A small piece of work between clock checks: a few episodes (at most `limit`),
        fewer once they add up to `ADVANCE_STEPS` steps, so a stop is seen within
        milliseconds however long the episodes are."""
        count = 16 if limit is None else min(16, limit)
        first_step = self.steps
        for done in range(1, count + 1):
            self.run_episode()
            if self.steps - first_step >= ADVANCE_STEPS:
                return done
        return count

    def episode_in_progress(self) -> bool:
        return self._obs is not None

    def current_observation(self) -> Any:
        """The observation the agent is about to act on (None between episodes)."""
        return self._obs


def continue_run(
    current: Settings | None, wanted: Settings, episodes_done: int
) -> tuple[Settings, str | None]:
    """The hyperparameters to train on with, and what to tell the person, if anything.

    Raising the episode budget of an agent that has trained continues its run:
    the epsilon decay keeps its length in episodes (the decay fraction is scaled
    down to match), so epsilon carries on from where it is instead of jumping
    back up. When the decay fraction or the epsilons are changed too, they are
    taken as asked; if that sends epsilon back up, the note says so plainly.
    """
    if current is None or episodes_done <= 0:
        return wanted, None
    hp, note = wanted, None
    same_fraction = math.isclose(
        wanted.epsilon_decay_fraction, current.epsilon_decay_fraction, rel_tol=1e-5, abs_tol=1e-9
    )
    if wanted.episodes > current.episodes and same_fraction:
        decay_episodes = current.epsilon_decay_fraction * current.episodes
        hp = wanted.replace(epsilon_decay_fraction=min(1.0, decay_episodes / wanted.episodes))
        note = (
            f"Budget raised to {wanted.episodes:,} episodes: the run goes on from episode "
            f"{episodes_done:,} with epsilon on its schedule (decay fraction "
            f"{hp.epsilon_decay_fraction:.4g}: the decay still ends at episode "
            f"{decay_episodes:,.0f})."
        )
    before, after = current.epsilon_at(episodes_done), hp.epsilon_at(episodes_done)
    if after > before + 1e-6:
        note = (
            f"Exploration restarts: with these settings epsilon goes back up from "
            f"{before:.3g} to {after:.3g} at episode {episodes_done:,}."
        )
    return hp, note
