"""The wrapper catalog: Gymnasium wrappers a person can switch on and off.

- `params`: `Param`, one typed, ranged parameter that parses text;
- `catalog`: `WrapperSpec`, `CATALOG`, `get_spec`, `WrapperChoice`,
  and the CLI syntax `parse_wrapper_spec` / `format_wrapper_spec`;
- `fits`: what each wrapper needs from the env, as reasons;
- `custom`: our own wrappers `ScaleReward`, `StepPenalty`, `DistanceShaping`;
- `build`: `build_env`, `build_env_lenient`, `check_choices`.

    >>> from tui_gym.core.wrappers import build_env, parse_wrapper_spec
    >>> env = build_env("CartPole-v1", choices=[parse_wrapper_spec("StepPenalty:penalty=0.1")])
    >>> env
    <StepPenalty<TimeLimit<OrderEnforcing<PassiveEnvChecker<CartPoleEnv<CartPole-v1>>>>>>
"""

from tui_gym.core.params import Param
from tui_gym.core.wrappers.build import (
    UnknownEnvError,
    build_env,
    build_env_lenient,
    check_choices,
)
from tui_gym.core.wrappers.catalog import (
    CATALOG,
    MAX_CHAIN,
    UnknownWrapperError,
    WrapperChoice,
    WrapperMismatchError,
    WrapperSpec,
    check_chain_length,
    format_wrapper_spec,
    get_spec,
    parse_wrapper_spec,
)
from tui_gym.core.wrappers.custom import DistanceShaping, ScaleReward, StepPenalty

__all__ = [
    "CATALOG",
    "MAX_CHAIN",
    "DistanceShaping",
    "Param",
    "ScaleReward",
    "StepPenalty",
    "UnknownEnvError",
    "UnknownWrapperError",
    "WrapperChoice",
    "WrapperMismatchError",
    "WrapperSpec",
    "build_env",
    "build_env_lenient",
    "check_chain_length",
    "check_choices",
    "format_wrapper_spec",
    "get_spec",
    "parse_wrapper_spec",
]
