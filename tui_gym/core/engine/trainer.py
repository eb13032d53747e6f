"""The trainer: one learner trained in chunks, with bounded statistics and snapshots.

`Trainer` trains on the game's model with the compiled loop, or on the Gymnasium env a
transition at a time (`step`: the animated board, and what no model follows). `run`
works in chunks of milliseconds; an episode in progress carries over between calls.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from tui_gym.core.engine import loop, rules
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.engine.stats import (
    EpisodeStats,
    RollingWindow,
    Series,
    StepEvent,
    TrainingSnapshot,
)
from tui_gym.core.obskey import ObservationKeyer

__all__ = [
    "EPISODE_RETURNS",
    "SERIES_NAMES",
    "StopFlag",
    "Trainer",
    "TrainerProgress",
    "continue_run",
]

SERIES_NAMES = ("return", "length", "td_error", "epsilon")
# The series of each episode's own return (bucket means, not rolling means): what the run
# history records as a run's `return` curve.
EPISODE_RETURNS = "episode_return"
ENV_CHUNK_STEPS = 256  # env-loop steps after which `run` checks the clock and its stop flag
CHUNK_SECONDS = 0.004  # the model loop's calls aim at this long
MAX_CALL_EPISODES = 65_536  # episodes one call of the model loop reports at most
RATE_SECONDS = 1.0  # the episodes per second shown are over about this much training time
# What `progress` hands over besides the version and the rate, by the trainer's own names.
_CARRIED = ("episodes", "steps", "seconds", "windows", "series", "last", "engine")


class StopFlag(Protocol):
    """What `Trainer.run` checks between pieces of work (a `threading.Event` will do)."""

    def is_set(self) -> bool: ...


@dataclass(frozen=True)
class TrainerProgress:
    """A trainer's counts and bounded statistics, to hand to another trainer."""

    episodes: int
    steps: int
    seconds: float
    windows: dict[str, RollingWindow]
    series: dict[str, Series]
    last: EpisodeStats | None
    version: int
    engine: str = "model"
    rate: float = 0.0  # the episodes per second last shown


class Trainer:
    """Trains `agent` on `model` (`later`: each later phase's start step and model) when
    given, else on `env`; `seed` seeds the env's first reset; `reason` says which loop
    trains and why."""

    def __init__(
        self,
        env: gym.Env,
        agent: Any,
        keyer: ObservationKeyer,
        *,
        model: ModelArrays | None = None,
        later: Sequence[tuple[int, ModelArrays]] = (),
        seed: int | None = None,
        reason: str = "",
        window: int = 1000,
        series_capacity: int = 256,
        publish_interval: float = 0.1,
    ) -> None:
        self.env = env
        self.agent = agent
        self.keyer = keyer
        self.model = model
        self.phases = ((0, model), *later) if model is not None else ()
        self.seed = seed
        self.reason = reason
        self.publish_interval = publish_interval
        self.on_status: Callable[[str], None] | None = None  # hears "compiling…" lines
        self.status = ""
        self.episodes = 0
        self.steps = 0
        self.seconds = 0.0
        self.windows = {name: RollingWindow(window) for name in SERIES_NAMES}
        self.series = {name: Series(series_capacity) for name in (*SERIES_NAMES, EPISODE_RETURNS)}
        self.last: EpisodeStats | None = None
        self.engine = "model" if model is not None else "env"
        self._version = 0
        self._samples: deque[tuple[float, int]] = deque(maxlen=64)  # (seconds, episodes)
        self._rate = 0.0
        # The model loop's episode in progress and its buffers.
        self._cursor = loop.Cursor()
        self._out = np.zeros((MAX_CALL_EPISODES, loop.COLUMNS))
        self._log = rules.new_log()
        self._call_steps = 4096
        # The env loop's episode in progress.
        self._obs: Any = None
        self._row = 0
        self._pending = -1  # the next action, chosen before the update (SARSA)
        self._episode: list[float] = []  # return, length, sum of |TD|, first action
        self._warmed = False
        self._env_seeded = False
        self.latest: TrainingSnapshot = self.snapshot()

    # --- which loop ----------------------------------------------------------------
    def _use(self, engine: str) -> None:
        """Train with `engine` from now on (the other loop's episode in progress is dropped)."""
        if engine == self.engine:
            return
        self.engine = engine
        self._cursor.drop()
        self._obs = None
        self.agent.begin_episode()
        self._samples.clear()
        self._rate = 0.0

    def _warm(self) -> None:
        """Compile the learner's loop, saying so (once: it is cached on disk)."""
        if not self._warmed:
            agent = self.agent
            if loop.warm([(agent.name, agent.arrays(), agent.compiled_params())], self._say):
                self._say("")
            self._warmed = True

    def _say(self, text: str) -> None:
        self.status = text
        if self.on_status is not None:
            self.on_status(text)
        self.publish()

    # --- chunks ----------------------------------------------------------
    def run(
        self,
        episodes: int | None = None,
        seconds: float | None = None,
        stop: StopFlag | None = None,
        on_publish: Callable[[TrainingSnapshot], None] | None = None,
        call_seconds: float = CHUNK_SECONDS,
    ) -> int:
        """Run until `episodes` more episodes, `seconds` elapse, or `stop` is set (checked
        between chunks); the episodes finished. Publishes a snapshot to `latest` (and
        `on_publish`) every `publish_interval` seconds and at the end."""
        if episodes is None and seconds is None and stop is None:
            raise ValueError("run() needs episodes, seconds or a stop event")
        self._use("model" if self.model is not None else "env")
        if self.model is not None:
            self._warm()
        start = began = time.perf_counter()
        next_publish = start + self.publish_interval
        self._samples.append((self.seconds, self.episodes))
        done = 0
        while episodes is None or done < episodes:
            quota = None if episodes is None else episodes - done
            if self.model is not None:
                done += self._chunk_model(quota, call_seconds)
            else:
                done += self._chunk_env(quota)
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

    def _chunk_model(self, quota: int | None, call_seconds: float = CHUNK_SECONDS) -> int:
        """One call of the compiled loop (about `call_seconds`); the episodes it finished."""
        assert self.model is not None
        limit = MAX_CALL_EPISODES if quota is None else min(quota, MAX_CALL_EPISODES)
        max_steps = self._call_steps
        for start, model in self.phases:  # the phase in force, up to where the next starts
            if start > self.steps:
                max_steps = min(max_steps, start - self.steps)
                break
            self.model = model
        began = time.perf_counter()
        out, log = self._out, self._log
        done, steps = loop.play(self.agent, self.model, self._cursor, limit, max_steps, out, log)
        elapsed = time.perf_counter() - began
        if elapsed > 0 and steps:  # aim the next call at call_seconds
            wanted = steps * call_seconds / elapsed
            self._call_steps = int(min(max(wanted, 256), 1 << 22))
        self.steps += steps
        if done:
            self._record(self._out[:done])
        return done

    def _record(self, rows: np.ndarray) -> None:
        """Count finished episodes (rows of `loop.COLUMNS`) into the windows and curves."""
        for name, values in zip(SERIES_NAMES, rows.T[: len(SERIES_NAMES)], strict=True):
            self.series[name].push_many(self.windows[name].push_many(values))
        self.series[EPISODE_RETURNS].push_many(rows[:, 0])
        ret, length, td, eps, first = rows[-1].tolist()
        self.last = EpisodeStats(ret, int(length), td, eps, int(first))
        self.episodes += len(rows)

    def _chunk_env(self, quota: int | None) -> int:
        """A few episodes on the env (at most `quota`, fewer after `ENV_CHUNK_STEPS` steps)."""
        count = 16 if quota is None else min(16, quota)
        first_step = self.steps
        done = 0
        while done < count:
            if self.step().episode_done is not None:
                done += 1
                if self.steps - first_step >= ENV_CHUNK_STEPS:
                    break
        return done

    # --- one transition on the env ------------------------------------------------------
    def step(self, explain: bool = False) -> StepEvent:
        """Take one transition on the env (with `explain`, the learner's record of it)."""
        self._use("env")
        self._warm()
        agent = self.agent
        if self._obs is None:
            seed = None if self._env_seeded else self.seed
            self._env_seeded = self._env_seeded or seed is not None
            # A world that changes goes on at the step the trainer has reached.
            options = {"world_steps": self.steps} if len(self.phases) > 1 else None
            obs, _ = self.env.reset(seed=seed, options=options)
            agent.begin_episode()
            self._obs, self._row, self._pending = obs, agent.row(self.keyer.key(obs)), -1
            self._episode = [0.0, 0.0, 0.0, -1.0]  # return, steps, |TD| sum, first action
        obs, row = self._obs, self._row
        action = self._pending if self._pending >= 0 else agent.act(self.keyer.key(obs))
        next_obs, reward, terminated, truncated, _ = self.env.step(action)
        reward, terminated, truncated = float(reward), bool(terminated), bool(truncated)
        next_row = agent.row(self.keyer.key(next_obs))
        next_action, td = agent.learn(
            row, action, reward, next_row, terminated, truncated, explain=explain
        )
        record = agent.last_update if explain else None
        self.steps += 1
        totals = self._episode
        totals[0] += reward
        totals[1] += 1
        totals[2] += td
        if totals[3] < 0:
            totals[3] = action
        episode, length = self.episodes + 1, int(totals[1])
        finished = None
        if terminated or truncated:
            ret, _, total, first = totals
            self._record(np.array([[ret, length, total / length, agent.epsilon, first]]))
            agent.end_episodes(1)
            finished = self.last
            self._obs = None
        else:
            self._obs, self._row, self._pending = next_obs, next_row, next_action
        return StepEvent(
            obs, action, reward, next_obs, terminated, truncated, finished, episode, length, record
        )

    def run_episode(self) -> EpisodeStats:
        """Finish one more episode and return its statistics."""
        self.run(episodes=1)
        assert self.last is not None
        return self.last

    def episode_in_progress(self) -> bool:
        """Whether an episode has started and not ended."""
        return self._obs is not None or self._cursor.live

    def current_observation(self) -> Any:
        """The observation the agent is about to act on, on the env (None otherwise)."""
        return self._obs

    # --- snapshots -----------------------------------------------------------------------
    def publish(self, callback: Callable[[TrainingSnapshot], None] | None = None) -> None:
        snap = self.snapshot()
        self.latest = snap
        if callback is not None:
            callback(snap)

    def _recent_rate(self) -> float:
        """Episodes per second over about the last `RATE_SECONDS` of training."""
        samples = self._samples
        now, count = self.seconds, self.episodes
        if not samples or samples[-1] != (now, count):
            samples.append((now, count))
        # The first sample kept is the newest one at least RATE_SECONDS old, if any.
        while len(samples) > 2 and now - samples[1][0] >= RATE_SECONDS:
            samples.popleft()
        then, before = samples[0]
        if now > then and count > before:
            self._rate = (count - before) / (now - then)
        return self._rate

    def snapshot(self) -> TrainingSnapshot:
        """An immutable copy of the statistics, the action values and any traces."""
        q, keys = self.agent.table()
        self._version += 1
        w = self.windows
        return TrainingSnapshot(
            engine=self.engine,
            episodes=self.episodes,
            steps=self.steps,
            seconds=self.seconds,
            episodes_per_second=self._recent_rate(),
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
            status=self.status,
            traces=self.agent.eligibility(),
        )

    def progress(self) -> TrainerProgress:
        """Counts and statistics so far (to carry on elsewhere)."""
        carried = {name: getattr(self, name) for name in _CARRIED}
        return TrainerProgress(**carried, version=self._version, rate=self._recent_rate())

    def restore(self, progress: TrainerProgress) -> None:
        """Carry on from `progress` (made by this trainer's agent)."""
        for name in _CARRIED:
            setattr(self, name, getattr(progress, name))
        self._version = progress.version
        self._samples.clear()  # the rate goes on from the one shown
        self._rate = progress.rate
        self.publish()

    @property
    def remaining(self) -> int:
        return max(0, self.agent.hp.episodes - self.episodes)


def continue_run(current: Any, wanted: Any, episodes_done: int) -> tuple[Any, str | None]:
    """The hyperparameters to train on with, and what to tell the person, if anything:
    a raised budget keeps the epsilon decay's length in episodes (epsilon carries on);
    other changes are taken as asked, with a note if epsilon goes back up."""
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
