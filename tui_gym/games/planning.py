"""`PlanModel`: what a game hands the Plan view, `tui-gym plan` and the book to plan on;
`value_panel` (a grid of state values) and `line` (states along one axis) draw values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP, evaluate, with_horizon
from tui_gym.core.mdp.evaluation import expected_value

__all__ = ["PlanModel", "StateLine"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class StateLine:
    """States along one axis: model state `states[i]` sits at `x[i]`; `numbers[s, a]` is the
    number action `a` stands for in state `s` (a stake), named by `action_label`."""

    x_label: str
    states: IntArray
    x: FloatArray
    numbers: FloatArray
    action_label: str

    def policy_numbers(self, policy: FloatArray) -> FloatArray:
        """Per state on the line: the smallest number among the actions the policy takes
        (the book breaks ties the same way in its figures)."""
        taken = np.asarray(policy)[self.states] > 0
        numbers = np.where(taken, self.numbers[self.states], np.inf)
        return np.asarray(numbers.min(axis=1))


@dataclass(frozen=True, eq=False)
class PlanModel:
    """A game's model for planning: `base_of[s]`, the base state whose action model state
    `s` takes; `shown[b]`, the model state base state `b` shows; `gamma` to start with;
    `horizon` of the exact values; `offered` `[B, A]` (None: every action everywhere)."""

    model: FiniteMDP
    gamma: float = 1.0
    horizon: int | None = None
    base_of: IntArray | None = None
    shown: IntArray | None = None
    value_panel: Callable[[FloatArray], Heatmap] | None = None
    line: StateLine | None = None
    offered: npt.NDArray[np.bool_] | None = None

    def __post_init__(self) -> None:
        if self.model.horizon is not None:
            object.__setattr__(self, "model", with_horizon(self.model, None))
        identity = np.arange(self.model.n_states, dtype=np.int64)
        for name in ("base_of", "shown"):
            array = getattr(self, name)
            array = identity if array is None else np.asarray(array, dtype=np.int64)
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    @property
    def n_base(self) -> int:
        """How many base states there are."""
        assert self.shown is not None
        return len(self.shown)

    def base_values(self, v: FloatArray) -> FloatArray:
        """`[B]`: the values the base states show."""
        return np.asarray(v)[self.shown]

    def base_rows(self, table: npt.ArrayLike) -> FloatArray:
        """`[B, ...]`: the rows of a model-state table the base states show."""
        return np.asarray(table)[self.shown]

    def allowed(self) -> npt.NDArray[np.bool_]:
        """`[S, A]`: the actions each model state offers."""
        if self.offered is None:
            return np.ones((self.model.n_states, self.model.n_actions), dtype=bool)
        return np.asarray(self.offered, dtype=bool)[self.base_of]

    def model_policy(self, base_policy: npt.ArrayLike) -> FloatArray:
        """`[S, A]`: a policy of the base states (`[B, A]` probabilities) on every model state."""
        return np.asarray(base_policy, dtype=np.float64)[self.base_of]

    def limited_value(self, policy: npt.ArrayLike) -> float:
        """The policy's exact value as the rest of the tool counts it: undiscounted, over
        the episode limit, averaged over the start states."""
        return evaluate(with_horizon(self.model, self.horizon), policy).value

    def start_value(self, v: FloatArray) -> float:
        """The start distribution's average of `v`."""
        return expected_value(self.model, np.asarray(v, dtype=np.float64))
