"""Q-learning gives, with the same seeds, the numbers it gave when these were recorded.

The fingerprints below were recorded from the engine: on the Gymnasium env one
transition at a time (dense and sparse tables) and on the game's model with
the compiled loop, the same table bit for bit, step count and epsilon. Sparse
tables are compared by the values of the states updated (the learner also
gives rows to next states it never left). A change of the rule, the acting,
the sampler or the order of the random draws shows here.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from tui_gym.algorithms import Learner, QLearning
from tui_gym.core.engine.trainer import Trainer
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.wrappers import WrapperChoice, build_env
from tui_gym.session.session import Session

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
        ("Blackjack-v1", {"episodes": 1500}, (), ("205f25dbcce693cc", 2121)),
        ("tui_gym/GridWorld-v0", {**GRID, "episodes": 60}, (), ("a34c2e23b875d8b6", 2106)),
        ("tui_gym/GridWorld-v0", {**GRID, "episodes": 60},
         (WrapperChoice("TimeAwareObservation", {"normalize_time": True}),),
         ("d0ec87558eee01dc", 2997)),
    ],
    ids=["blackjack", "gridworld", "gridworld-sparse-keys"],
)
def test_the_env_loop_gives_the_recorded_run(env_id, hp, choices, expected) -> None:
    env = build_env(env_id, {}, choices)
    keyer = ObservationKeyer(env.observation_space)
    learner = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=3)
    trainer = Trainer(env, learner, keyer, seed=5)
    trainer.run(episodes=hp["episodes"])
    assert (fingerprint(learner), trainer.steps) == expected
    assert learner.epsilon == 0.05


@pytest.mark.parametrize(
    ("game", "hp", "expected"),
    [
        ("blackjack", {"episodes": 20_000}, ("406f891e3d421b5b", 29736)),
        ("gridworld", {**GRID, "episodes": 600, "learning_rate_schedule": "constant"},
         ("3bbab5ac569e1b34", 7370)),
        ("frozenlake", {"episodes": 3_000}, ("a06baa8248c649f9", 19292)),
    ],
    ids=["blackjack", "gridworld", "frozenlake"],
)
def test_the_model_loop_gives_the_recorded_run(game, hp, expected) -> None:
    session = Session(game, hp=hp, seed=3)
    assert session.trainer.engine == "model"
    session.trainer.run(episodes=hp["episodes"])
    assert (fingerprint(session.agent), session.trainer.steps) == expected
    assert session.agent.epsilon == 0.05
