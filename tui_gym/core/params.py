"""`Param`: one typed, ranged parameter that parses what a person types."""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Param", "ParamError", "ParamValue", "digits_note", "read_number", "shown_value"]

ParamValue = int | float | bool | str

_TRUE, _FALSE = ("true", "t", "yes", "y", "on", "1"), ("false", "f", "no", "n", "off", "0")
_BOOL_WORDS = {**dict.fromkeys(_TRUE, True), **dict.fromkeys(_FALSE, False)}

_DIGITS = r"[0-9]+(?:_[0-9]+)*"
_INTEGER = re.compile(rf"[+-]?{_DIGITS}", re.ASCII)
_DECIMAL = re.compile(
    rf"[+-]?(?:{_DIGITS}(?:\.(?:{_DIGITS})?)?|\.{_DIGITS})(?:[eE][+-]?{_DIGITS})?", re.ASCII
)
_WORDS = {"inf": math.inf, "infinity": math.inf, "nan": math.nan}
# Beyond every float, and far below the 4,300 digits Python refuses to convert to an int.
_MAX_INT_DIGITS = 400
_FLOAT_MAX = float(np.finfo(np.float64).max)


def finite_number(name: str, value: float, *, minimum: float | None = None) -> float:
    """`value` as a float; ValueError naming `name` unless finite and at least `minimum`."""
    number = float(value)
    if not math.isfinite(number) or (minimum is not None and number < minimum):
        bound = "" if minimum is None else f" >= {minimum:g}"
        raise ValueError(f"{name} must be a finite number{bound}, got {value!r}")
    return number


def read_number(text: str) -> int | float | None:
    """The number `text` (ASCII digits) spells, or None: an `int` (±inf beyond every float) or
    a `float` (possibly inf or nan)."""
    text = text.strip()
    if _INTEGER.fullmatch(text):
        negative = text.startswith("-")
        digits = text.lstrip("+-").replace("_", "").lstrip("0") or "0"
        if len(digits) > _MAX_INT_DIGITS or int(digits) > _FLOAT_MAX:
            return -math.inf if negative else math.inf
        return -int(digits) if negative else int(digits)
    if _DECIMAL.fullmatch(text):
        return float(text)  # huge exponents read as inf, tiny ones as 0.0
    word = text.lower()
    sign = -1.0 if word.startswith("-") else 1.0
    value = _WORDS.get(word.lstrip("+-"))
    return None if value is None else sign * value


def digits_note(raw: object) -> str:
    """' (digits 0-9 only)' when `raw` is text holding digits of another script ('١٢',
    '²'), which `read_number` does not read; '' otherwise."""
    if isinstance(raw, str) and any(ch.isdigit() and not ch.isascii() for ch in raw):
        return " (digits 0-9 only)"
    return ""


def typed_text(value: Any) -> str:
    """A value as a person types it: `true`, `0.333333`, `4x4`."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return f"{value:g}" if isinstance(value, float) else str(value)


def shown_value(raw: object) -> str:
    """`raw` as an error message quotes it: its repr, shortened when long."""
    if isinstance(raw, bool | np.bool_ | str | float | np.floating):
        text = repr(raw if not isinstance(raw, np.generic) else raw.item())
        if len(text) <= 40:
            return text
        if isinstance(raw, str):
            return f"{raw[:12] + '…' + raw[-6:]!r} ({len(raw):,} characters)"
        return text[:40] + "…"
    if isinstance(raw, numbers.Integral):
        value = int(raw)
        if value.bit_length() <= 128:
            return repr(value)
        digits = int(value.bit_length() * math.log10(2)) + 1
        return f"{'a negative' if value < 0 else 'an'} integer of about {digits:,} digits"
    if raw is None:
        return "None"
    # Lists and dicts from files and requests: their repr can be huge or nested deeply.
    return f"a {type(raw).__name__}"


def _number_text(value: float) -> str:
    """`1` for 1.0, `0.25` for 0.25: how bounds read in messages."""
    return str(int(value)) if float(value).is_integer() else repr(float(value))


class ParamError(ValueError):
    """A value a `Param` refuses; `out_of_range` tells out of range from not a number."""

    def __init__(self, param: Param, raw: object, out_of_range: bool) -> None:
        self.param = param
        self.raw = raw
        self.out_of_range = out_of_range
        self.shown = shown_value(raw)
        if out_of_range:
            self.reason = f"is out of range: {self.shown} is not in {param.describe_range()}"
        else:
            self.reason = f"must be {param.expected()}, got {self.shown}{digits_note(raw)}"
        super().__init__(f"{param.label} {self.reason}")


@dataclass(frozen=True)
class Param:
    """One parameter: its type, default, range and help. `owner` (a wrapper's name) prefixes
    its name in messages, `title` labels it in a form, `min_inclusive=False` makes the lower
    bound exclusive; a `str` param is a choice among `choices`, read case-insensitively;
    `when` (name, value) says it matters only while that other param has that value.
    """

    name: str
    kind: type  # int, float, bool or str
    default: ParamValue
    minimum: float | None = None
    maximum: float | None = None
    help: str = ""
    owner: str = ""
    title: str = ""
    min_inclusive: bool = True
    choices: tuple[str, ...] = ()
    when: tuple[str, ParamValue] | None = None

    def __post_init__(self) -> None:
        if self.kind not in (int, float, bool, str):
            raise TypeError(
                f"Param {self.name}: kind must be int, float, bool or str, not {self.kind}"
            )
        if (self.kind is str) != bool(self.choices):
            raise TypeError(f"Param {self.name}: a str param, and only one, has choices")
        # A catalog entry whose default is out of its own range is a bug: fail at import.
        if self.parse(self.default) != self.default:
            raise ValueError(f"Param {self.name}: default {self.default!r} is not canonical")

    @property
    def label(self) -> str:
        """`Owner.name`, or just `name` outside a spec."""
        return f"{self.owner}.{self.name}" if self.owner else self.name

    def applies(self, values: Mapping[str, Any]) -> bool:
        """Whether this param matters with these values of the others (see `when`)."""
        return self.when is None or values.get(self.when[0]) == self.when[1]

    def describe_range(self) -> str:
        """The valid values, as shown in help and errors: `[1, 100000]`, `true or false`."""
        if self.kind is bool:
            return "true or false"
        if self.kind is str:
            return "one of " + ", ".join(self.choices)
        bracket = "[" if self.min_inclusive else "("
        low = "(-inf" if self.minimum is None else f"{bracket}{_number_text(self.minimum)}"
        high = "inf)" if self.maximum is None else f"{_number_text(self.maximum)}]"
        return f"{low}, {high}"

    def expected(self) -> str:
        """What a valid value is, in words: `an integer in [1, 100000]`."""
        if self.kind in (bool, str):
            return self.describe_range()
        noun = "an integer" if self.kind is int else "a number"
        return f"{noun} in {self.describe_range()}"

    def parse(self, raw: object) -> ParamValue:
        """`raw` (text or a number) as this param's type, in range; else `ParamError`, e.g.
        `TimeLimit.max_episode_steps must be an integer in [1, 100000], got 'abc'`."""
        value = self._convert(raw)
        if value is None:
            raise ParamError(self, raw, out_of_range=False)
        if isinstance(value, str):
            return value
        if self.kind is not bool and not self._in_range(value):
            raise ParamError(self, raw, out_of_range=True)
        if self.kind is float:
            return float(value)
        return value

    def _in_range(self, value: int | float) -> bool:
        if abs(value) > _FLOAT_MAX:  # ±inf, or an int beyond every float: no setting is that large
            return False
        low = self.minimum
        if low is not None and (value < low or (not self.min_inclusive and value == low)):
            return False
        return self.maximum is None or value <= self.maximum

    def _convert(self, raw: object) -> ParamValue | None:
        """`raw` as `kind` (±inf for numbers too large to hold), or None when it is not one."""
        if self.kind is str:
            word = raw.strip().lower() if isinstance(raw, str) else None
            return next((c for c in self.choices if c.lower() == word), None)
        if self.kind is bool:
            if isinstance(raw, np.bool_ | numbers.Integral) and int(raw) in (0, 1):
                return bool(raw)
            return _BOOL_WORDS.get(raw.strip().lower()) if isinstance(raw, str) else None
        if isinstance(raw, bool | np.bool_):
            return None  # True is an int to Python, not to a person typing a step count
        number: int | float | None
        if isinstance(raw, numbers.Integral):
            number = int(raw)
        elif isinstance(raw, numbers.Real):
            number = float(raw)
        elif isinstance(raw, str):
            number = read_number(raw)
        else:
            return None
        if number is None or (isinstance(number, float) and math.isnan(number)):
            return None
        if self.kind is int and isinstance(number, float) and math.isfinite(number):
            if not number.is_integer():
                return None
            number = int(number)
        return number
