"""CliffWalking's model and seed batches on it, for the tests of `compare`'s batches."""

from __future__ import annotations

import gymnasium as gym

from tui_gym.algorithms import algorithm
from tui_gym.core.experiments.seed_batch import ModelSteps, SeedBatch
from tui_gym.core.mdp import FiniteMDP, model_from_env


def cliff_model() -> FiniteMDP:
    env = gym.make("CliffWalking-v1", max_episode_steps=200)
    model = model_from_env(env)
    env.close()
    assert isinstance(model, FiniteMDP)
    return model


def seed_batch(name: str, model: FiniteMDP, seeds: int, episodes: int, **hp: object) -> SeedBatch:
    """`seeds` learners of algorithm `name` on `model`, one step of each per batch step."""
    cls = algorithm(name)
    settings = cls.settings({"episodes": episodes, **hp})
    return SeedBatch(cls, settings, ModelSteps(model, seeds, 1), seeds, episodes,
                     seed=2, model=model)
