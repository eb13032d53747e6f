"""Hyperparameter schemas and validated values for the learners."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from tui_gym.core.engine.rules import epsilon_at
from tui_gym.core.params import Param

__all__ = ["COMMON_PARAMS", "LEARNING_RATE_SCHEDULES", "Choice", "Field", "Settings"]

# Shared by every learner: `constant` (always the learning rate) and `visits`
# (`max(learning_rate, 1/n)` for the n-th update of a (state, action)).
LEARNING_RATE_SCHEDULES = ("constant", "visits")


@dataclass(frozen=True)
class Choice:
    """A parameter that takes one of a few words; the same surface as `Param`."""

    name: str
    choices: tuple[str, ...]
    default: str
    help: str = ""
    title: str = ""
    kind: ClassVar[type] = str

    def __post_init__(self) -> None:
        if self.default not in self.choices:
            raise ValueError(f"Choice {self.name}: default {self.default!r} is not a choice")

    def describe_range(self) -> str:
        return " or ".join(self.choices)

    def expected(self) -> str:
        return f"one of {', '.join(self.choices)}"

    def parse(self, raw: object) -> str:
        """The word itself when `raw` is one of the choices (spaces and case ignored)."""
        word = raw.strip().lower() if isinstance(raw, str) else None
        if word not in self.choices:
            raise ValueError(f"{self.name} must be {self.expected()}, got {raw!r}")
        return word


Field = Param | Choice

COMMON_PARAMS: tuple[Field, ...] = (
    Param("learning_rate", float, 0.001, 0.0, 1.0, "step size of each update",
          title="Learning rate", min_inclusive=False),
    Param("discount", float, 1.0, 0.0, 1.0, "weight of the next state's value", title="Discount"),
    Param("epsilon_start", float, 1.0, 0.0, 1.0, "exploration at the start", title="Epsilon start"),
    Param("epsilon_final", float, 0.05, 0.0, 1.0, "exploration after decay", title="Epsilon final"),
    Param("epsilon_decay_fraction", float, 0.5, 0.0, 1.0,
          "share of the budget spent decaying epsilon", title="Decay fraction"),
    Param("episodes", int, 200_000, 1, 1_000_000_000, "training budget", title="Episodes"),
    Param("initial_value", float, 0.0, -1e6, 1e6,
          "Q of every pair before any update: above every return, it draws the agent to "
          "what it has not tried (optimistic starts)", title="Initial Q"),
    Choice("learning_rate_schedule", LEARNING_RATE_SCHEDULES, "visits",
           "constant: the learning rate; visits: max(learning rate, 1/n) for the n-th update "
           "of a state-action", title="Step sizes"),
)

# The λ learners' traces (compiled as `replacing: bool`).
TRACES = Choice("traces", ("replacing", "accumulating"), "replacing",
                "replacing: a visited state's (or pair's) trace is set to 1; accumulating: 1 "
                "is added", title="Traces")


class Settings(Mapping[str, Any]):
    """One validated value per field of a schema (`hp.discount`, `hp["discount"]`); text is
    parsed as a form sends it, unknown names are refused."""

    def __init__(self, schema: Sequence[Field], values: Mapping[str, Any] | None = None) -> None:
        by_name = {f.name: f for f in schema}
        given = dict(values or {})
        unknown = sorted(set(given) - set(by_name))
        if unknown:
            raise ValueError(f"unknown hyperparameter(s): {', '.join(unknown)}")
        parsed = {f.name: f.parse(given[f.name]) if f.name in given else f.default for f in schema}
        start, final = parsed.get("epsilon_start"), parsed.get("epsilon_final")
        if isinstance(start, float) and isinstance(final, float) and final > start:
            raise ValueError(f"epsilon_final ({final:g}) must not exceed epsilon_start ({start:g})")
        self.__dict__["_schema"] = tuple(schema)
        self.__dict__["_values"] = parsed

    # --- reading ------------------------------------------------------------
    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)  # keeps pickling and copying away from the values
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(f"no hyperparameter {name!r}") from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("Settings are immutable; use replace()")

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __hash__(self) -> int:
        return hash(tuple(self._values.items()))

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self._values.items())
        return f"Settings({inner})"

    @property
    def schema(self) -> tuple[Field, ...]:
        return self._schema

    # --- deriving -----------------------------------------------------------
    def epsilon_at(self, episode: int) -> float:
        """The exploration rate for a 0-based episode number (linear decay, then flat)."""
        return float(epsilon_at(float(episode), float(self.epsilon_start),
                                float(self.epsilon_final),
                                float(self.epsilon_decay_fraction * self.episodes)))

    def to_dict(self) -> dict[str, Any]:
        return dict(self._values)

    def replace(self, **changes: Any) -> Settings:
        """New settings with some values changed (validated like the first)."""
        return Settings(self._schema, {**self._values, **changes})
