"""Q-learning as a learner gives exactly the numbers of `QAgent` and `batched_q_update`.

Same inputs, same table bit for bit: one transition at a time against
`QAgent.update`, batches with duplicate (state, action) pairs against
`batched_q_update`, under both step-size schedules. Then whole runs: today's
scalar `Trainer` and `VectorTrainer`, driving the learner through its protocol,
end with the same table, step count and epsilon as with `QAgent`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import tui_gym.core.vector.trainer as vector_trainer
from tests.game_support import form_of
from tui_gym.algorithms import QLearning, Transitions
from tui_gym.core.agent import Hyperparameters, QAgent
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.training import Trainer
from tui_gym.core.vector import VectorTrainer
from tui_gym.core.wrappers import WrapperChoice, build_env

SCHEDULES = [
    Hyperparameters(learning_rate=lr, discount=0.9, learning_rate_schedule=schedule)
    for schedule in ("visits", "constant")
    for lr in (0.001, 0.3, 1.0)
]


def _name(hp: Hyperparameters) -> str:
    return f"{hp.learning_rate_schedule}-{hp.learning_rate}"


def _no_truncation(n: int) -> np.ndarray:
    return np.zeros(n, dtype=bool)


@pytest.mark.parametrize("hp", SCHEDULES, ids=_name)
def test_batches_with_duplicates_equal_batched_q_update(hp: Hyperparameters) -> None:
    rng = np.random.default_rng(1)
    agent = QAgent(3, hp, n_states=6, seed=0)
    learner = QLearning(3, hp, n_states=6, seed=0)
    for size in (40, 1, 2, 40, 7, 40):  # 40 transitions over 18 cells: many duplicates
        for _ in range(5):
            keys, actions = rng.integers(0, 6, size), rng.integers(0, 3, size)
            rewards, terminated = rng.normal(size=size), rng.random(size) < 0.3
            next_keys = rng.integers(0, 6, size)
            expected = vector_trainer.batched_q_update(
                agent, keys, actions, rewards, terminated, next_keys)
            td = learner.update(Transitions(keys, actions, rewards, next_keys, terminated,
                                            _no_truncation(size)))
            assert np.array_equal(td, expected)
            assert np.array_equal(learner.q, agent.q)
    assert np.array_equal(learner.counts, agent.counts)
    assert np.array_equal(learner.visits, agent.visits)


@pytest.mark.parametrize("hp", SCHEDULES, ids=_name)
def test_one_at_a_time_equals_q_agent_update(hp: Hyperparameters) -> None:
    rng = np.random.default_rng(2)
    agent = QAgent(3, hp, n_states=6, seed=0)
    learner = QLearning(3, hp, n_states=6, seed=0)
    for _ in range(300):
        key, action, next_key = int(rng.integers(6)), int(rng.integers(3)), int(rng.integers(6))
        reward, terminated = float(rng.normal()), bool(rng.random() < 0.3)
        expected = agent.update(key, action, reward, terminated, next_key)
        assert learner.update_one(key, action, reward, next_key, terminated) == expected
    assert np.array_equal(learner.q, agent.q)
    assert np.array_equal(learner.counts, agent.counts)


def test_acting_draws_like_q_agent() -> None:
    hp = Hyperparameters(epsilon_start=0.5, epsilon_final=0.5)
    agent = QAgent(4, hp, n_states=5, seed=7)
    learner = QLearning(4, hp, n_states=5, seed=7)
    table = np.array([[0, 0, 0, 0], [1, 0, 1, 0], [0, 2, 0, 0], [3, 3, 3, 1], [0, 0, 0, 5.0]])
    agent.q[:] = table
    learner.q[:] = table
    keys = np.random.default_rng(0).integers(0, 5, 400)
    assert [learner.act(int(k)) for k in keys] == [agent.act(int(k)) for k in keys]
    assert [learner.greedy(int(k)) for k in keys] == [agent.greedy(int(k)) for k in keys]


class _ScalarShim:
    """What today's `Trainer` calls on an agent, answered by a learner."""

    def __init__(self, learner: QLearning) -> None:
        self.__dict__["learner"] = learner

    def __getattr__(self, name: str) -> Any:
        return getattr(self.learner, name)

    def update(self, key: Any, action: int, reward: float, terminated: bool,
               next_key: Any) -> float:
        return self.learner.update_one(key, action, reward, next_key, terminated)


@pytest.mark.parametrize(
    ("env_id", "hp", "episodes", "choices"),
    [
        ("Blackjack-v1", Hyperparameters(episodes=1500), 1500, ()),
        ("tui_gym/GridWorld-v0", Hyperparameters(discount=0.95, learning_rate=0.1, episodes=60),
         60, ()),
        ("tui_gym/GridWorld-v0", Hyperparameters(discount=0.95, learning_rate=0.1, episodes=60),
         60, (WrapperChoice("TimeAwareObservation", {"normalize_time": True}),)),
    ],
    ids=["blackjack", "gridworld", "gridworld-sparse-keys"],
)
def test_scalar_trainer_runs_the_same_with_the_learner(env_id, hp, episodes, choices) -> None:
    runs = []
    for make in (QAgent, QLearning):
        env = build_env(env_id, {}, choices)
        keyer = ObservationKeyer(env.observation_space)
        agent = make(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
        trainer = Trainer(env, agent if make is QAgent else _ScalarShim(agent), keyer, seed=5)
        trainer.run(episodes=episodes)
        runs.append((agent, trainer.steps))
    (agent, steps), (learner, learner_steps) = runs
    assert learner_steps == steps and learner.epsilon == agent.epsilon
    q, keys = agent.table()
    if keys is None:
        assert np.array_equal(learner.q, agent.q)
    else:  # same values per key (the learner also gives rows to next states it has not left)
        assert not learner.dense
        assert np.array_equal(learner.values(keys), q)
        assert learner.states_seen == agent.states_seen


class _LearnerVectorTrainer(VectorTrainer):
    def _choose(self, keys: np.ndarray) -> np.ndarray:
        return self.agent.act_batch(keys)


@pytest.mark.parametrize(
    ("env_id", "hp", "episodes", "num_envs"),
    [
        ("Blackjack-v1", Hyperparameters(episodes=20_000), 20_000, 256),
        ("tui_gym/GridWorld-v0", Hyperparameters(discount=0.95, learning_rate=0.1,
                                                 episodes=600, learning_rate_schedule="constant"),
         600, 32),
    ],
    ids=["blackjack", "gridworld"],
)
def test_vector_trainer_runs_the_same_with_the_learner(
    monkeypatch: pytest.MonkeyPatch, env_id, hp, episodes, num_envs
) -> None:
    env = build_env(env_id, {})
    keyer = ObservationKeyer(env.observation_space)
    agent = QAgent(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=5, num_envs=num_envs)
    trainer.run(episodes=episodes)
    trainer.run(episodes=3)  # quota tails step a handful of envs, down to one

    def learner_update(learner, keys, actions, rewards, terminated, next_keys):
        return learner.update(Transitions(keys, actions, rewards, next_keys, terminated,
                                          _no_truncation(len(keys))))

    monkeypatch.setattr(vector_trainer, "batched_q_update", learner_update)
    learner = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
    other = _LearnerVectorTrainer(env, learner, keyer, form=form_of(env), seed=5, num_envs=num_envs)
    other.run(episodes=episodes)
    other.run(episodes=3)
    assert other.steps == trainer.steps and learner.epsilon == agent.epsilon
    assert np.array_equal(learner.q, agent.q)
    assert np.array_equal(learner.counts, agent.counts)
