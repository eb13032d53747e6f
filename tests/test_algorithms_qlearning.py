"""Q-learning on both engines gives, with the same seeds, the numbers it always gave.

The fingerprints below were recorded from the one-rule-per-engine Q-learning
agent that came before the learner protocol (`QAgent` with the scalar
`Trainer`, `batched_q_update` in the vector trainer): the same table bit for
bit, step count and epsilon. Sparse tables are compared by the values of the
states updated (the learner also gives rows to next states it never left).
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from tests.game_support import form_of
from tui_gym.algorithms import Learner, QLearning
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.training import Trainer
from tui_gym.core.vector import VectorTrainer
from tui_gym.core.wrappers import WrapperChoice, build_env

GRID = {"discount": 0.95, "learning_rate": 0.1}


def fingerprint(learner: Learner) -> str:
    _, keys = learner.table()
    if keys is None:
        data = np.ascontiguousarray(learner.q).tobytes()
    else:
        data = repr(sorted(
            (repr(k), learner.values([k])[0].tobytes().hex()) for k in keys if learner.seen(k)
        )).encode()
    return hashlib.sha256(data).hexdigest()[:16]


@pytest.mark.parametrize(
    ("env_id", "hp", "choices", "expected"),
    [
        ("Blackjack-v1", {"episodes": 1500}, (), ("dc38b75b0c69c89d", 2155)),
        ("tui_gym/GridWorld-v0", {**GRID, "episodes": 60}, (), ("7e7bb091b63ca656", 2717)),
        ("tui_gym/GridWorld-v0", {**GRID, "episodes": 60},
         (WrapperChoice("TimeAwareObservation", {"normalize_time": True}),),
         ("8b6732bdb22f90a2", 3684)),
    ],
    ids=["blackjack", "gridworld", "gridworld-sparse-keys"],
)
def test_the_scalar_engine_gives_the_recorded_run(env_id, hp, choices, expected) -> None:
    env = build_env(env_id, {}, choices)
    keyer = ObservationKeyer(env.observation_space)
    learner = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
    trainer = Trainer(env, learner, keyer, seed=5)
    trainer.run(episodes=hp["episodes"])
    assert (fingerprint(learner), trainer.steps) == expected
    assert learner.epsilon == 0.05


@pytest.mark.parametrize(
    ("env_id", "hp", "num_envs", "expected"),
    [
        ("Blackjack-v1", {"episodes": 20_000}, 256, ("0736dae5e84524bb", 29811)),
        ("tui_gym/GridWorld-v0",
         {**GRID, "episodes": 600, "learning_rate_schedule": "constant"}, 32,
         ("80958992a7997960", 8664)),
    ],
    ids=["blackjack", "gridworld"],
)
def test_the_vector_engine_gives_the_recorded_run(env_id, hp, num_envs, expected) -> None:
    env = build_env(env_id, {})
    keyer = ObservationKeyer(env.observation_space)
    learner = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
    trainer = VectorTrainer(env, learner, keyer, form=form_of(env), seed=5, num_envs=num_envs)
    trainer.run(episodes=hp["episodes"])
    trainer.run(episodes=3)  # quota tails step a handful of envs, down to one
    assert (fingerprint(learner), trainer.steps) == expected
    assert learner.epsilon == 0.05
