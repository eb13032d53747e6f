"""`Param`: one typed, ranged parameter that parses what a person types.

Wrapper parameters, env arguments and hyperparameters are all `Param`s. A
CLI argument and a UI input field both arrive as text; `Param.parse` turns
that text into an `int`, `float` or `bool`, checks the inclusive range, and
otherwise raises a `ValueError` that names the field and what it accepts.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

__all__ = ["Param", "ParamValue"]

ParamValue = int | float | bool

_TRUE_WORDS = frozenset({"true", "t", "yes", "y", "on", "1"})
_FALSE_WORDS = frozenset({"false", "f", "no", "n", "off", "0"})


def _number_text(value: float) -> str:
    """`1` for 1.0, `0.25` for 0.25: how bounds read in messages."""
    return str(int(value)) if float(value).is_integer() else repr(float(value))


@dataclass(frozen=True)
class Param:
    """One parameter: its type, default, range and help.

    `owner` is e.g. the wrapper's name, filled in by `WrapperSpec`, so that
    error messages say `TimeLimit.max_episode_steps` rather than a bare field
    name. `title` is how a form labels it; `min_inclusive=False` makes the
    lower bound exclusive (a learning rate must be above 0).
    """

    name: str
    kind: type  # int, float or bool
    default: ParamValue
    minimum: float | None = None
    maximum: float | None = None
    help: str = ""
    owner: str = ""
    title: str = ""
    min_inclusive: bool = True

    def __post_init__(self) -> None:
        if self.kind not in (int, float, bool):
            raise TypeError(f"Param {self.name}: kind must be int, float or bool, not {self.kind}")
        # A catalog entry whose default is out of its own range is a bug: fail at import.
        if self.parse(self.default) != self.default:
            raise ValueError(f"Param {self.name}: default {self.default!r} is not canonical")

    @property
    def label(self) -> str:
        """`Owner.name`, or just `name` outside a spec."""
        return f"{self.owner}.{self.name}" if self.owner else self.name

    def describe_range(self) -> str:
        """The valid values, as shown in help and errors: `[1, 100000]`, `true or false`."""
        if self.kind is bool:
            return "true or false"
        bracket = "[" if self.min_inclusive else "("
        low = "(-inf" if self.minimum is None else f"{bracket}{_number_text(self.minimum)}"
        high = "inf)" if self.maximum is None else f"{_number_text(self.maximum)}]"
        return f"{low}, {high}"

    def expected(self) -> str:
        """What a valid value is, in words: `an integer in [1, 100000]`."""
        if self.kind is bool:
            return "true or false"
        noun = "an integer" if self.kind is int else "a number"
        return f"{noun} in {self.describe_range()}"

    def parse(self, raw: str | int | float | bool) -> ParamValue:
        """Convert `raw` (text or a number) to this param's type and check its range.

        Raises `ValueError` naming the field and its valid values, e.g.
        `TimeLimit.max_episode_steps must be an integer in [1, 100000], got 'abc'`.
        """
        value = self._convert(raw)
        if value is None or (
            self.kind is not bool
            and (
                (self.minimum is not None and value < self.minimum)
                or (self.minimum is not None and not self.min_inclusive and value == self.minimum)
                or (self.maximum is not None and value > self.maximum)
            )
        ):
            raise ValueError(f"{self.label} must be {self.expected()}, got {raw!r}")
        return value

    def _convert(self, raw: object) -> ParamValue | None:
        """`raw` as `kind`, or None when it does not read as one."""
        if self.kind is bool:
            if isinstance(raw, bool | np.bool_):
                return bool(raw)
            if isinstance(raw, numbers.Integral) and int(raw) in (0, 1):
                return bool(raw)
            if isinstance(raw, str):
                word = raw.strip().lower()
                if word in _TRUE_WORDS:
                    return True
                if word in _FALSE_WORDS:
                    return False
            return None
        if isinstance(raw, bool | np.bool_):
            return None  # True is an int to Python, not to a person typing a step count
        number: float | int
        if isinstance(raw, numbers.Integral):
            number = int(raw)
        elif isinstance(raw, numbers.Real):
            number = float(raw)
        elif isinstance(raw, str):
            text = raw.strip()
            try:
                number = int(text)
            except ValueError:
                try:
                    number = float(text)
                except ValueError:
                    return None
        else:
            return None
        if isinstance(number, float) and not math.isfinite(number):
            return None
        if self.kind is int:
            if isinstance(number, float):
                if not number.is_integer():
                    return None
                number = int(number)
            return number
        return float(number)
