"""The baseline: a tutorial-style Q-learning loop on Gymnasium's `Blackjack-v1`.

This is how Gymnasium's "Solving Blackjack with Q-Learning" tutorial trains,
written the tutorial's way: one `gym.make("Blackjack-v1")`, a
`defaultdict(lambda: np.zeros(n_actions))` Q-table keyed by the observation
tuple, epsilon-greedy with `env.action_space.sample()` and `np.argmax`, one
Python-level update per step. Only the hyperparameters are ours, so that the
comparison is about speed, not about settings: the same ones as the default
Blackjack agent (`Hyperparameters()`: discount 1, the "visits" step size
`max(lr, 1/n(s, a))`, epsilon from 1.0 to 0.05 linearly over the first half of
the budget).

To keep the baseline honest rather than a strawman, the loop leaves out what
only slows the tutorial down: no `RecordEpisodeStatistics` wrapper, no
`training_error` list, no progress bar. What remains is what any tutorial-style
loop must do per step: step the env, pick an action, update one Q-value.

`TutorialAgent.gap()` scores the agent's greedy policy exactly (the
`policy_value` dynamic programme; no sampling), as `Session.reference()` does
for our agent: unseen states get the tutorial's `np.argmax` of zeros (stick).
"""

from __future__ import annotations

import time
from collections import defaultdict
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from tui_gym.core.agent import Hyperparameters
from tui_gym.games.blackjack.solver import (
    POLICY_SHAPE,
    BlackjackRules,
    optimal_value,
    policy_value,
)

GAP_CHECK_EVERY = 10_000  # episodes between exact gap checks (as `Session.train`)


class TutorialAgent:
    """The tutorial's `BlackjackAgent`, with our default schedules (see the module docstring)."""

    def __init__(self, env: gym.Env, hp: Hyperparameters, seed: int = 0) -> None:
        self.env = env
        self.hp = hp
        self.n_actions = int(env.action_space.n)
        self.q_values: defaultdict[tuple, np.ndarray] = defaultdict(
            lambda: np.zeros(self.n_actions)
        )
        self.counts: defaultdict[tuple, np.ndarray] = defaultdict(
            lambda: np.zeros(self.n_actions, dtype=np.int64)
        )
        self.rng = np.random.default_rng(seed)
        env.action_space.seed(seed)
        self.episode = 0
        self.epsilon = hp.epsilon_at(0)

    def get_action(self, obs: tuple) -> int:
        if self.rng.random() < self.epsilon:
            return int(self.env.action_space.sample())
        return int(np.argmax(self.q_values[obs]))

    def update(
        self, obs: tuple, action: int, reward: float, terminated: bool, next_obs: tuple
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
        """The greedy policy as a `POLICY_SHAPE` array (0 stick, 1 hit) for `policy_value`."""
        policy = np.zeros(POLICY_SHAPE, dtype=np.int8)
        for obs, values in self.q_values.items():
            player, dealer, usable = (int(x) for x in obs)
            policy[player, dealer, usable] = int(np.argmax(values))
        return policy

    def gap(self, rules: BlackjackRules | None = None) -> float:
        """The exact distance of the greedy policy's value from the optimum's."""
        rules = rules or BlackjackRules()
        return optimal_value(rules) - policy_value(self.policy(), rules)


def train_episodes(agent: TutorialAgent, episodes: int) -> None:
    """The tutorial's training loop, for `episodes` more episodes."""
    env = agent.env
    for _ in range(episodes):
        obs, _info = env.reset()
        done = False
        while not done:
            action = agent.get_action(obs)
            next_obs, reward, terminated, truncated, _info = env.step(action)
            agent.update(obs, action, float(reward), terminated, next_obs)
            done = terminated or truncated
            obs = next_obs
        agent.decay_epsilon()


def make_agent(hp: Hyperparameters | None = None, seed: int = 0) -> TutorialAgent:
    """A fresh tutorial agent on a fresh `gym.make("Blackjack-v1")`, seeded."""
    env = gym.make("Blackjack-v1")
    env.reset(seed=seed)
    return TutorialAgent(env, hp or Hyperparameters(), seed=seed)


def episodes_per_second(seconds: float, hp: Hyperparameters | None = None, seed: int = 0) -> float:
    """Train a fresh agent for about `seconds`; its episodes per second."""
    agent = make_agent(hp, seed)
    done = 0
    batch = 500
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
    hp: Hyperparameters,
    seed: int = 0,
    cap_seconds: float | None = None,
    check_every: int = GAP_CHECK_EVERY,
) -> GapRun:
    """Train until the exact gap is at most `target` (checked every `check_every` episodes),
    the budget `hp.episodes` runs out, or `cap_seconds` pass."""
    start = time.perf_counter()
    agent = make_agent(hp, seed)
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
