"""The vector engine: many games stepped at once with numpy, any learner in batches.

- `blackjack.BatchedBlackjack`, `gridworld.BatchedGridWorld`: the games'
  rules on arrays of states, any subset stepped in one call;
- `plan.plan_for_env`: reads a built env's wrappers as a `VectorPlan`
  (game, time limit, reward transforms) or says why it has no batched form;
- `trainer.VectorTrainer`: an engine beside the scalar `Trainer` (engine
  "vector") that trains the same learner; `make_vector_trainer` builds one
  from a game id and wrapper choices;
- `vector_support(env_id, env_kwargs, choices)`: whether the vector engine
  can run a game with those wrappers, and a sentence saying so.

Batched forms exist for Blackjack and GridWorld with `TimeLimit`,
`ScaleReward`, `StepPenalty`, `ClipReward` and (GridWorld) `DistanceShaping`.
`FlattenObservation`, `TimeAwareObservation`, `DelayObservation` and
`StickyAction` keep the scalar engine: they change the observation keys or
bring randomness of their own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym

from tui_gym.core.vector.base import BatchStep
from tui_gym.core.vector.blackjack import BatchedBlackjack
from tui_gym.core.vector.gridworld import BatchedGridWorld
from tui_gym.core.vector.plan import NoBatchedForm, VectorPlan, plan_for_env
from tui_gym.core.vector.trainer import (
    DEFAULT_NUM_ENVS,
    VectorTrainer,
    make_vector_trainer,
)
from tui_gym.core.wrappers import WrapperChoice, build_env_lenient

__all__ = [
    "DEFAULT_NUM_ENVS",
    "BatchStep",
    "BatchedBlackjack",
    "BatchedGridWorld",
    "NoBatchedForm",
    "VectorPlan",
    "VectorTrainer",
    "make_vector_trainer",
    "plan_for_env",
    "vector_support",
]


def vector_support(
    env_id: str,
    env_kwargs: Mapping[str, Any] | None = None,
    choices: Sequence[WrapperChoice] = (),
) -> tuple[bool, str]:
    """Whether the vector engine can train on this game and wrapper choice, and why.

    The env is built as a `Session` builds it (choices that do not fit are
    left out, as there), read with `plan_for_env`, and closed. Returns e.g.
    `(True, "vector engine: Blackjack with StepPenalty")` or
    `(False, "scalar engine: DelayObservation has no batched form (...)")`.
    """
    try:
        env, _ = build_env_lenient(env_id, env_kwargs, choices)
    except (ValueError, TypeError, gym.error.Error) as error:
        return False, f"scalar engine: {error}"
    try:
        return True, plan_for_env(env).describe()
    except NoBatchedForm as error:
        return False, error.reason
    finally:
        env.close()
