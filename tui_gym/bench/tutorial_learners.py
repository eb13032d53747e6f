"""Baselines for every algorithm: tutorial-style loops, one Python update per step.

Each is written the way a tutorial writes its algorithm: one `gym.make`
env, `defaultdict(lambda: np.zeros(n_actions))` tables keyed by the
observation (made hashable), epsilon-greedy with `env.action_space.sample()`
and `np.argmax`, and the update rule in plain Python per step (Monte Carlo:
per episode, from a list of the episode's steps; Dyna-Q: a dict model and
`planning_steps` replayed transitions per real step). The hyperparameters
are the algorithm's defaults for the game, so that a comparison with our
vector engine is about speed, not settings.
"""

from __future__ import annotations

import random
import time
from collections import defaultdict
from collections.abc import Hashable
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import Settings

__all__ = ["TutorialLearner", "episodes_per_second"]


def _hashable(obs: Any) -> Hashable:
    """Observations as dict keys: dicts of arrays (GridWorld) become tuples."""
    if isinstance(obs, dict):
        return tuple(int(v) for key in sorted(obs) for v in np.ravel(obs[key]))
    if isinstance(obs, np.ndarray):
        return tuple(obs.ravel().tolist())
    return obs


class TutorialLearner:
    """One algorithm (by registry name) the tutorial way on one env."""

    def __init__(self, env: gym.Env, algorithm: str, hp: Settings, seed: int = 0) -> None:
        self.env = env
        self.algorithm = algorithm
        self.hp = hp
        space = env.action_space
        assert isinstance(space, gym.spaces.Discrete), space  # a tabular agent's actions
        self.n_actions = int(space.n)
        zeros = lambda: np.zeros(self.n_actions)  # noqa: E731 - the tutorial's idiom
        self.q: defaultdict[Hashable, np.ndarray] = defaultdict(zeros)
        self.q_b: defaultdict[Hashable, np.ndarray] = defaultdict(zeros)  # Double Q's second
        self.counts: defaultdict[Hashable, np.ndarray] = defaultdict(zeros)
        self.model: dict[tuple[Hashable, int], tuple[float, Hashable, bool]] = {}
        self.seen: list[tuple[Hashable, int]] = []  # Dyna-Q's pairs, in the order first tried
        self.rng = np.random.default_rng(seed)
        self.coin = random.Random(seed)
        env.action_space.seed(seed)
        self.episode = 0
        self.epsilon = hp.epsilon_at(0)

    # --- acting ------------------------------------------------------------------
    def values(self, obs: Hashable) -> np.ndarray:
        if self.algorithm == "double-q":
            return self.q[obs] + self.q_b[obs]
        return self.q[obs]

    def get_action(self, obs: Hashable) -> int:
        if self.rng.random() < self.epsilon:
            return int(self.env.action_space.sample())
        return int(np.argmax(self.values(obs)))

    def _step_size(self, counts: np.ndarray, action: int) -> float:
        counts[action] += 1
        if self.hp.learning_rate_schedule == "visits":
            return max(self.hp.learning_rate, 1.0 / counts[action])
        return self.hp.learning_rate

    # --- the rules -----------------------------------------------------------------
    def td_update(self, obs: Hashable, action: int, reward: float, terminated: bool,
                  next_obs: Hashable, next_action: int | None) -> None:
        gamma = self.hp.discount
        name = self.algorithm
        if name == "double-q":
            table, other = (self.q, self.q_b) if self.coin.random() < 0.5 else (self.q_b, self.q)
            best = int(np.argmax(table[next_obs]))
            future = (not terminated) * other[next_obs][best]
            lr = self._step_size(self.counts[obs], action)
            table[obs][action] += lr * (reward + gamma * future - table[obs][action])
            return
        if name == "sarsa":
            assert next_action is not None
            future = self.q[next_obs][next_action]
        elif name == "expected-sarsa":
            values = self.q[next_obs]
            probs = np.full(self.n_actions, self.epsilon / self.n_actions)
            best = values == values.max()
            probs += best * (1 - self.epsilon) / best.sum()
            future = float(probs @ values)
        else:  # q-learning and dyna-q
            future = float(np.max(self.q[next_obs]))
        future *= not terminated
        lr = self._step_size(self.counts[obs], action)
        self.q[obs][action] += lr * (reward + gamma * future - self.q[obs][action])
        if name == "dyna-q":
            if (obs, action) not in self.model:
                self.seen.append((obs, action))
            self.model[(obs, action)] = (reward, next_obs, terminated)
            pairs = self.seen
            for _ in range(self.hp.planning_steps):
                s, a = pairs[self.coin.randrange(len(pairs))]
                r, s2, done = self.model[(s, a)]
                target = r + gamma * (not done) * float(np.max(self.q[s2]))
                step = max(self.hp.learning_rate, 1.0 / max(self.counts[s][a], 1))
                self.q[s][a] += step * (target - self.q[s][a])

    def mc_update(self, steps: list[tuple[Hashable, int, float]]) -> None:
        g = 0.0
        first: dict[tuple[Hashable, int], int] = {}
        if self.hp.first_visit:
            for t, (obs, action, _) in enumerate(steps):
                first.setdefault((obs, action), t)
        for t in range(len(steps) - 1, -1, -1):
            obs, action, reward = steps[t]
            g = reward + self.hp.discount * g
            if self.hp.first_visit and first[(obs, action)] != t:
                continue
            lr = self._step_size(self.counts[obs], action)
            self.q[obs][action] += lr * (g - self.q[obs][action])

    # --- the loop --------------------------------------------------------------------
    def train_episode(self) -> None:
        env = self.env
        obs = _hashable(env.reset()[0])
        sarsa = self.algorithm == "sarsa"
        action = self.get_action(obs)
        steps: list[tuple[Hashable, int, float]] = []
        done = False
        while not done:
            next_obs, reward, terminated, truncated, _ = env.step(action)
            next_obs = _hashable(next_obs)
            next_action = self.get_action(next_obs) if sarsa else None
            if self.algorithm == "monte-carlo":
                steps.append((obs, action, float(reward)))
            else:
                self.td_update(obs, action, float(reward), terminated, next_obs, next_action)
            done = terminated or truncated
            obs = next_obs
            if not done:
                action = next_action if next_action is not None else self.get_action(obs)
        if steps:
            self.mc_update(steps)
        self.episode += 1
        self.epsilon = self.hp.epsilon_at(self.episode)


def episodes_per_second(env_id: str, env_kwargs: dict[str, Any], algorithm: str,
                        hp: Settings, seconds: float, seed: int = 0) -> float:
    """Train a fresh tutorial learner for about `seconds`; its episodes per second."""
    env = gym.make(env_id, **env_kwargs)
    env.reset(seed=seed)
    learner = TutorialLearner(env, algorithm, hp, seed)
    done = 0
    start = time.perf_counter()
    try:
        while True:
            for _ in range(20):
                learner.train_episode()
            done += 20
            elapsed = time.perf_counter() - start
            if elapsed >= seconds:
                return done / elapsed
    finally:
        env.close()
