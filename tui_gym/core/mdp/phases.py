"""`Phases`: a world that changes as it is played, as the model of each phase."""

from __future__ import annotations

from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass

from tui_gym.core.mdp.model import FiniteMDP, ModelError

__all__ = ["Phases"]


@dataclass(frozen=True, eq=False)
class Phases:
    """The model of each phase (`models[i]` from step `starts[i]` on); `ModelError` when the
    phases do not make one world (a first start other than 0, starts not increasing, or
    models of different sizes)."""

    models: tuple[FiniteMDP, ...]
    starts: tuple[int, ...]

    def __post_init__(self) -> None:
        models, starts = tuple(self.models), tuple(int(s) for s in self.starts)
        if not models or len(models) != len(starts):
            raise ModelError(f"{len(models)} models for {len(starts)} phase starts")
        if starts[0] != 0 or any(b <= a for a, b in zip(starts, starts[1:], strict=False)):
            raise ModelError(f"phases must start at step 0 and then later each, got {starts}")
        sizes = {(m.n_states, m.n_actions) for m in models}
        if len(sizes) > 1:
            raise ModelError(f"the phases' models differ in size: {sorted(sizes)}")
        object.__setattr__(self, "models", models)
        object.__setattr__(self, "starts", starts)

    @classmethod
    def of(cls, model: FiniteMDP) -> Phases:
        """A world that never changes."""
        return cls((model,), (0,))

    @classmethod
    def listed(cls, phases: Sequence[tuple[int, FiniteMDP]]) -> Phases:
        """From (start step, model) pairs."""
        return cls(tuple(m for _, m in phases), tuple(s for s, _ in phases))

    def index_at(self, steps: int) -> int:
        """The phase in force for the transition after `steps` transitions (steps >= 0)."""
        return max(0, bisect_right(self.starts, int(steps)) - 1)
