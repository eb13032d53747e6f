"""The catalog of swappable wrappers: what each one is, takes and needs."""

from __future__ import annotations

import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import (
    ClipReward,
    DelayObservation,
    FlattenObservation,
    StickyAction,
    TimeAwareObservation,
    TimeLimit,
)

from tui_gym.core.params import Param, ParamValue, shown_value
from tui_gym.core.wrappers.custom import DistanceShaping, ScaleReward, StepPenalty
from tui_gym.core.wrappers.fits import (
    fits_any,
    fits_delay,
    fits_distance,
    fits_flatten,
    fits_time_aware,
    fits_time_limit,
)

__all__ = [
    "CATALOG", "MAX_CHAIN", "UnknownWrapperError", "WrapperChoice", "WrapperMismatchError",
    "WrapperSpec", "check_chain_length", "format_wrapper_spec", "get_spec", "parse_wrapper_spec",
]

MAX_CHAIN = 32  # wrappers in one chain: far more than any lesson needs, far below a stack's depth


class UnknownWrapperError(ValueError):
    """A wrapper name that is not in the catalog."""


class WrapperMismatchError(ValueError):
    """A wrapper that does not fit the env it was asked to wrap; `reason` says why."""

    def __init__(self, reason: str, choice: WrapperChoice | None = None) -> None:
        super().__init__(reason)
        self.reason = reason
        self.choice = choice


def replace_time_limit(env: gym.Env, max_episode_steps: int) -> TimeLimit:
    """`TimeLimit(env, n)`, except that a `TimeLimit` right below is replaced, not stacked on.

    Stacked limits can only shorten each other, so without this the limit
    `gym.make` puts on a registered env (say 300) could never be raised.
    """
    if isinstance(env, TimeLimit):
        env = env.env
    return TimeLimit(env, max_episode_steps)


def _check_clip_bounds(values: Mapping[str, Any]) -> None:
    if values["min_reward"] > values["max_reward"]:
        raise ValueError(
            f"ClipReward.min_reward ({values['min_reward']!r}) must be <= "
            f"ClipReward.max_reward ({values['max_reward']!r})"
        )


# -- catalog entries ------------------------------------------------------------

FitCheck = Callable[[gym.Env, Mapping[str, Any] | None], str | None]


@dataclass(frozen=True)
class WrapperSpec:
    """One catalog entry: a wrapper a person can switch on, and what it takes.

    `factory(env, **values)` builds the wrapper; `requirement(env, values)`
    returns why it cannot wrap `env` (None when it can); `cross_check(values)`
    rejects combinations no single param can (ClipReward's min > max).
    """

    name: str
    summary: str
    params: tuple[Param, ...]
    changes_observation: bool
    factory: Callable[..., gym.Env] = field(repr=False, compare=False)
    requirement: FitCheck = field(default=fits_any, repr=False, compare=False)
    cross_check: Callable[[Mapping[str, Any]], None] | None = field(
        default=None, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        owned = tuple(replace(param, owner=self.name) for param in self.params)
        object.__setattr__(self, "params", owned)
        names = [param.name for param in owned]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.name}: duplicate parameter names {names}")

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(param.name for param in self.params)

    def param(self, name: str) -> Param:
        for param in self.params:
            if param.name == name:
                return param
        raise KeyError(name)

    def defaults(self) -> dict[str, ParamValue]:
        return {param.name: param.default for param in self.params}

    def validate(self, values: Mapping[str, Any]) -> dict[str, ParamValue]:
        """Parse each given value, fill in defaults, reject unknown names.

        The result is in the order of `params`.
        """
        unknown = [name for name in values if name not in self.param_names]
        if unknown:
            valid = (
                f"valid: {', '.join(self.param_names)}" if self.params else "it takes no parameters"
            )
            raise ValueError(
                f"{self.name} has no parameter {', '.join(shown_value(n) for n in unknown[:3])}"
                f"; {valid}"
            )
        parsed = {
            param.name: param.parse(values[param.name]) if param.name in values else param.default
            for param in self.params
        }
        if self.cross_check is not None:
            self.cross_check(parsed)
        return parsed

    def fits(self, env: gym.Env, values: Mapping[str, Any] | None = None) -> str | None:
        """None when this wrapper can wrap `env`, else a reason a person can act on.

        With `values`, also checks what depends on them (a TimeLimit longer than
        one already inside cannot lengthen it).
        """
        checked = None if values is None else self.validate(values)
        return self.requirement(env, checked)

    def build(self, env: gym.Env, values: Mapping[str, Any] | None = None) -> gym.Env:
        """Wrap `env`; raises `WrapperMismatchError` when it does not fit."""
        checked = self.validate(values or {})
        reason = self.requirement(env, checked)
        if reason is not None:
            raise WrapperMismatchError(reason, WrapperChoice(self.name, tuple(checked.items())))
        return self.factory(env, **checked)


CATALOG: dict[str, WrapperSpec] = {
    spec.name: spec
    for spec in (
        WrapperSpec(
            name="TimeLimit",
            summary="Cuts each episode off after N steps (truncated, not terminated): "
            "the goal must be reached in time.",
            params=(
                Param(
                    "max_episode_steps", int, default=100, minimum=1, maximum=100_000,
                    help="steps after which the episode is truncated",
                ),
            ),
            changes_observation=False,
            factory=replace_time_limit,
            requirement=fits_time_limit,
        ),
        WrapperSpec(
            name="FlattenObservation",
            summary="Turns the observation into one flat vector (one-hot for discrete parts): "
            "same information, a different shape to learn from.",
            params=(),
            changes_observation=True,
            factory=FlattenObservation,
            requirement=fits_flatten,
        ),
        WrapperSpec(
            name="TimeAwareObservation",
            summary="Adds the step count to the observation, so the same position early and "
            "near the time limit become different states.",
            params=(
                Param(
                    "flatten", bool, default=True,
                    help="flatten the result into one vector (discrete parts one-hot)",
                ),
                Param(
                    "normalize_time", bool, default=False,
                    help="time as a fraction of the limit in [0, 1] instead of a step count",
                ),
            ),
            changes_observation=True,
            factory=TimeAwareObservation,
            requirement=fits_time_aware,
        ),
        WrapperSpec(
            name="StickyAction",
            summary="With probability p the env repeats the previous action instead of yours: "
            "the world no longer obeys exactly, so plans must be robust.",
            params=(
                Param(
                    "repeat_action_probability", float, default=0.25, minimum=0.0, maximum=0.99,
                    help="chance that a step repeats the previous action (Machado et al.: 0.25)",
                ),
                Param(
                    "repeat_action_duration", int, default=1, minimum=1, maximum=100,
                    help="how many steps a repeat lasts once it starts",
                ),
            ),
            changes_observation=False,
            factory=StickyAction,
        ),
        WrapperSpec(
            name="DelayObservation",
            summary="Shows each observation `delay` steps late (zeros at first): "
            "the agent must act on stale information.",
            params=(
                Param(
                    "delay", int, default=1, minimum=1, maximum=100,
                    help="steps by which observations arrive late",
                ),
            ),
            changes_observation=True,
            factory=DelayObservation,
            requirement=fits_delay,
        ),
        WrapperSpec(
            name="ClipReward",
            summary="Clamps each reward into [min, max]: big wins and losses start to look "
            "alike, which changes what is worth chasing.",
            params=(
                Param(
                    "min_reward", float, default=-1.0, minimum=-1000.0, maximum=1000.0,
                    help="lowest reward let through",
                ),
                Param(
                    "max_reward", float, default=1.0, minimum=-1000.0, maximum=1000.0,
                    help="highest reward let through",
                ),
            ),
            changes_observation=False,
            factory=ClipReward,
            cross_check=_check_clip_bounds,
        ),
        WrapperSpec(
            name="ScaleReward",
            summary="Multiplies every reward by a factor: for factor > 0 the best policy stays "
            "the same, but the values learned and the pace of learning change.",
            params=(
                Param(
                    "factor", float, default=10.0, minimum=-100.0, maximum=100.0,
                    help="multiplier applied to every reward",
                ),
            ),
            changes_observation=False,
            factory=ScaleReward,
        ),
        WrapperSpec(
            name="StepPenalty",
            summary="Subtracts a small cost from every step's reward: dawdling gets expensive, "
            "so shorter episodes win.",
            params=(
                Param(
                    "penalty", float, default=0.01, minimum=0.0, maximum=10.0,
                    help="cost subtracted from each step's reward",
                ),
            ),
            changes_observation=False,
            factory=StepPenalty,
        ),
        WrapperSpec(
            name="DistanceShaping",
            summary="Adds -k x distance-to-target to each step's reward (the tutorial's "
            "Option 2): a dense hint that speeds learning but can mislead if k is large.",
            params=(
                Param(
                    "k", float, default=0.1, minimum=0.0, maximum=10.0,
                    help="reward lost per cell of distance still to go",
                ),
            ),
            changes_observation=False,
            factory=DistanceShaping,
            requirement=fits_distance,
        ),
    )
}

_BY_FOLDED_NAME = {name.casefold(): spec for name, spec in CATALOG.items()}


def get_spec(name: str) -> WrapperSpec:
    """The catalog entry called `name` (case does not matter)."""
    spec = CATALOG.get(name) or _BY_FOLDED_NAME.get(name.strip().casefold())
    if spec is None:
        raise UnknownWrapperError(
            f"unknown wrapper {shown_value(name)}; known wrappers: {', '.join(CATALOG)}"
        )
    return spec


# -- choices --------------------------------------------------------------------


@dataclass(frozen=True)
class WrapperChoice:
    """One wrapper picked by a person, with its values: hashable, params sorted by name.

    Build one with `WrapperChoice.make(name, **params)`, which validates through
    the catalog and fills in defaults.
    """

    name: str
    params: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        known = _BY_FOLDED_NAME.get(self.name.strip().casefold())
        if known is not None:
            object.__setattr__(self, "name", known.name)
        items = self.params.items() if isinstance(self.params, Mapping) else self.params
        object.__setattr__(self, "params", tuple(sorted((str(k), v) for k, v in items)))

    def values(self) -> dict[str, Any]:
        return dict(self.params)

    @property
    def spec(self) -> WrapperSpec:
        return get_spec(self.name)

    @classmethod
    def make(cls, name: str, **params: Any) -> WrapperChoice:
        spec = get_spec(name)
        return cls(spec.name, tuple(spec.validate(params).items()))

    def __str__(self) -> str:
        return format_wrapper_spec(self)


def _format_value(value: Any) -> str:
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))  # repr round-trips exactly, and has no np.float64(...)
    return str(value)


def format_wrapper_spec(choice: WrapperChoice) -> str:
    """`Name` or `Name:key=value,...` (keys in the catalog's order), the inverse of parsing."""
    if not choice.params:
        return choice.name
    values = choice.values()
    try:
        order = [name for name in get_spec(choice.name).param_names if name in values]
    except UnknownWrapperError:
        order = []
    order += sorted(name for name in values if name not in order)
    return f"{choice.name}:" + ",".join(f"{k}={_format_value(values[k])}" for k in order)


def parse_wrapper_spec(text: str) -> WrapperChoice:
    """Read the CLI syntax `Name` or `Name:key=value,key=value` into a validated choice.

    Examples: `TimeLimit:max_episode_steps=50`, `ClipReward:min_reward=-1,max_reward=1`.
    """
    syntax = "expected Name or Name:key=value,key=value"
    shown = shown_value(text)
    name, colon, rest = text.strip().partition(":")
    name = name.strip()
    if not name:
        raise ValueError(f"wrapper spec {shown} has no wrapper name; {syntax}")
    params: dict[str, str] = {}
    if colon and rest.strip():
        for item in rest.split(","):
            key, equals, value = item.partition("=")
            key, value = key.strip(), value.strip()
            if not equals or not key or not value:
                raise ValueError(
                    f"wrapper spec {shown}: {shown_value(item.strip())} is not key=value; {syntax}"
                )
            if key in params:
                raise ValueError(f"wrapper spec {shown} sets {shown_value(key)} twice")
            params[key] = value
    return WrapperChoice.make(name, **params)


def check_chain_length(count: int) -> None:
    """`ValueError` for a chain of more than `MAX_CHAIN` wrappers."""
    if count > MAX_CHAIN:
        raise ValueError(f"a chain of {count:,} wrappers: a chain holds at most {MAX_CHAIN}")
