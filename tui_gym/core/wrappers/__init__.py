"""The wrapper catalog: Gymnasium wrappers a person can switch on and off."""

from tui_gym.core.params import Param
from tui_gym.core.wrappers.build import UnknownEnvError, build_env, build_env_lenient, check_choices
from tui_gym.core.wrappers.catalog import (
    CATALOG,
    MAX_CHAIN,
    UnknownWrapperError,
    WrapperChoice,
    WrapperMismatchError,
    check_chain_length,
    format_wrapper_spec,
    get_spec,
    parse_wrapper_spec,
)

__all__ = [
    "CATALOG", "MAX_CHAIN", "Param", "UnknownEnvError", "UnknownWrapperError", "WrapperChoice",
    "WrapperMismatchError", "build_env", "build_env_lenient", "check_chain_length",
    "check_choices", "format_wrapper_spec", "get_spec", "parse_wrapper_spec",
]
