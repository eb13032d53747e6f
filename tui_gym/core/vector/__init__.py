"""The vector engine: many episodes stepped at once with numpy, any learner in batches.

- `base`: `BatchStep`, the `BatchedEnv` protocol and `BatchedForm`, the
  recipe a game hands the engine (the engine knows no game by name);
- `model.BatchedModel`: any game with an exact model, stepped from its
  transition arrays (`model_form` is its recipe);
- `plan.plan_for_env`: reads a built env's wrappers as a `VectorPlan`
  (the game's form, time limit, reward transforms) or says why it has no
  batched form;
- `trainer.VectorTrainer`: an engine beside the scalar `Trainer` (engine
  "vector") that trains the same learner; `make_vector_trainer` builds one
  from a game id and wrapper choices.

Batched forms take `TimeLimit`, `ScaleReward`, `StepPenalty`, `ClipReward`
and, for games that report a distance, `DistanceShaping`.
`FlattenObservation`, `TimeAwareObservation`, `DelayObservation` and
`StickyAction` keep the scalar engine: they change the observation keys or
bring randomness of their own.
"""

from __future__ import annotations

from tui_gym.core.vector.base import BatchedEnv, BatchedForm, BatchStep
from tui_gym.core.vector.model import BatchedModel, model_form
from tui_gym.core.vector.plan import NoBatchedForm, VectorPlan, plan_for_env
from tui_gym.core.vector.trainer import (
    DEFAULT_NUM_ENVS,
    VectorTrainer,
    make_vector_trainer,
)

__all__ = [
    "DEFAULT_NUM_ENVS",
    "BatchStep",
    "BatchedEnv",
    "BatchedForm",
    "BatchedModel",
    "NoBatchedForm",
    "VectorPlan",
    "VectorTrainer",
    "make_vector_trainer",
    "model_form",
    "plan_for_env",
]
