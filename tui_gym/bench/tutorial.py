"""The baseline: a tutorial-style Q-learning loop on the game's own Gymnasium env.

This is how Gymnasium's Q-learning tutorial trains (its card-game agent),
written the tutorial's way and run on any game of the registry: one
`gym.make(...)` of the game's id and arguments, a
`defaultdict(lambda: np.zeros(n_actions))` Q-table keyed by the observation,
epsilon-greedy with `env.action_space.sample()` and `np.argmax`, one
Python-level update per step. Only the hyperparameters are ours, so that the
comparison is about speed, not about settings: the game's default ones (the
discount, the "visits" step size `max(lr, 1/n(s, a))`, epsilon from 1.0 to
0.05 linearly over the first half of the budget).

To keep the baseline honest rather than a strawman, the loop leaves out what
only slows the tutorial down: no `RecordEpisodeStatistics` wrapper, no
`training_error` list, no progress bar. What remains is what any tutorial-style
loop must do per step: step the env, pick an action, update one Q-value.

`TutorialAgent.gap()` scores the agent's greedy policy exactly, with the
game's own oracle (no sampling), as `Session.reference()` does for our agent:
unseen states get the tutorial's `np.argmax` of zeros (the first action).
"""

from __future__ import annotations

import time
from collections import defaultdict
from collections.abc import Hashable, Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import Settings
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.games import Game

GAP_CHECK_EVERY = 10_000  # episodes between exact gap checks (as `Session.train`)


def _key(obs: Any) -> Hashable:
    """An observation as the tutorial keys its table: as it comes (tuples, ints)."""
    if isinstance(obs, np.ndarray):
        return tuple(obs.tolist())
    if isinstance(obs, np.integer):
        return int(obs)
    return obs


class TutorialAgent:
    """The tutorial's agent, with the game's default schedules (see the module docstring)."""

    def __init__(
        self, env: gym.Env, hp: Settings, game: Game, kwargs: Mapping[str, Any],
        seed: int = 0,
    ) -> None:
        self.env = env
        self.hp = hp
        self.game = game
        self.kwargs = dict(kwargs)
        self.n_actions = len(game.action_names)
        self.q_values: defaultdict[Hashable, np.ndarray] = defaultdict(
            lambda: np.zeros(self.n_actions)
        )
        self.counts: defaultdict[Hashable, np.ndarray] = defaultdict(
            lambda: np.zeros(self.n_actions, dtype=np.int64)
        )
        self.rng = np.random.default_rng(seed)
        env.action_space.seed(seed)
        self.episode = 0
        self.epsilon = hp.epsilon_at(0)
        self._changes = GameChanges.of(env, game.episode_limit(self.kwargs))

    def get_action(self, obs: Hashable) -> int:
        if self.rng.random() < self.epsilon:
            return int(self.env.action_space.sample())
        return int(np.argmax(self.q_values[obs]))

    def update(
        self, obs: Hashable, action: int, reward: float, terminated: bool, next_obs: Hashable
    ) -> None:
        future_q_value = (not terminated) * np.max(self.q_values[next_obs])
        temporal_difference = (
            reward + self.hp.discount * future_q_value - self.q_values[obs][action]
        )
        n = self.counts[obs]
        n[action] += 1
        lr = max(self.hp.learning_rate, 1.0 / n[action])  # the "visits" schedule
        self.q_values[obs][action] += lr * temporal_difference

    def decay_epsilon(self) -> None:
        self.episode += 1
        self.epsilon = self.hp.epsilon_at(self.episode)

    def policy(self) -> np.ndarray:
        """The greedy policy on the game's base states, one-hot rows: `np.argmax`'s choice."""
        states = self.game.states.base_observations(self.kwargs)
        assert not isinstance(states, NotAvailable), states
        one_hot = np.zeros((len(states), self.n_actions))
        for row, obs in enumerate(states):
            values = self.q_values.get(_key(obs))
            one_hot[row, int(np.argmax(values)) if values is not None else 0] = 1.0
        return one_hot

    def gap(self) -> float:
        """The exact distance of the greedy policy's value from the optimum's."""
        reference = self.game.oracle.reference(self.policy(), self.kwargs, self._changes)
        assert not isinstance(reference, NotAvailable), reference
        return float(reference.figures["gap"])


def train_episodes(agent: TutorialAgent, episodes: int) -> None:
    """The tutorial's training loop, for `episodes` more episodes."""
    env = agent.env
    for _ in range(episodes):
        obs, _info = env.reset()
        obs = _key(obs)
        done = False
        while not done:
            action = agent.get_action(obs)
            next_obs, reward, terminated, truncated, _info = env.step(action)
            next_obs = _key(next_obs)
            agent.update(obs, action, float(reward), terminated, next_obs)
            done = terminated or truncated
            obs = next_obs
        agent.decay_epsilon()


def make_agent(
    game: Game, kwargs: Mapping[str, Any], hp: Settings | None = None, seed: int = 0
) -> TutorialAgent:
    """A fresh tutorial agent on a fresh `gym.make` of the game, seeded."""
    import tui_gym.envs
    from tui_gym.session.session import default_settings

    tui_gym.envs.register_envs()
    normal = game.normalize_kwargs(kwargs)
    env = gym.make(game.env_id, **game.make_kwargs(normal))
    env.reset(seed=seed)
    hp = hp or default_settings(game, "q-learning", normal)
    return TutorialAgent(env, hp, game, normal, seed=seed)


def episodes_per_second(
    seconds: float, game: Game, kwargs: Mapping[str, Any], hp: Settings, seed: int = 0
) -> float:
    """Train a fresh agent for about `seconds`; its episodes per second."""
    agent = make_agent(game, kwargs, hp, seed)
    done = 0
    batch = 50
    start = time.perf_counter()
    while True:
        train_episodes(agent, batch)
        done += batch
        elapsed = time.perf_counter() - start
        if elapsed >= seconds:
            agent.env.close()
            return done / elapsed


@dataclass(frozen=True)
class GapRun:
    """How a run toward a target gap went."""

    seconds: float  # wall time, building the env included
    episodes: int
    gap: float  # the last gap checked
    reached: bool  # False: stopped by the budget or the time cap (seconds is a lower bound)


def time_to_gap(
    target: float,
    game: Game,
    kwargs: Mapping[str, Any],
    hp: Settings,
    seed: int = 0,
    cap_seconds: float | None = None,
    check_every: int = GAP_CHECK_EVERY,
) -> GapRun:
    """Train until the exact gap is at most `target` (checked every `check_every` episodes),
    the budget `hp.episodes` runs out, or `cap_seconds` pass."""
    start = time.perf_counter()
    agent = make_agent(game, kwargs, hp, seed)
    done = 0
    gap = float("inf")
    while done < hp.episodes:
        n = min(check_every, hp.episodes - done)
        train_episodes(agent, n)
        done += n
        gap = agent.gap()
        if gap <= target:
            break
        if cap_seconds is not None and time.perf_counter() - start >= cap_seconds:
            break
    seconds = time.perf_counter() - start
    agent.env.close()
    return GapRun(seconds, done, gap, gap <= target)
