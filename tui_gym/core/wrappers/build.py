"""Building an env from an id and a list of wrapper choices."""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym

import tui_gym.envs
from tui_gym.core.wrappers.catalog import (
    WrapperChoice,
    WrapperMismatchError,
    WrapperSpec,
    check_chain_length,
    get_spec,
)
from tui_gym.core.wrappers.chain import env_label

__all__ = ["UnknownEnvError", "build_env", "build_env_lenient", "check_choices"]

Kwargs = Mapping[str, Any] | None
Choices = Sequence[WrapperChoice]


class UnknownEnvError(ValueError):
    """An env id Gymnasium does not know (one line, with the nearest known ids)."""

    def __init__(self, env_id: str) -> None:
        near = difflib.get_close_matches(env_id, list(gym.registry), n=3, cutoff=0.75)
        hint = f"; did you mean {' or '.join(repr(n) for n in near)}?" if near else ""
        super().__init__(f"unknown environment {env_id!r}{hint}")
        self.env_id = env_id


def _assemble(
    env_id: str, env_kwargs: Kwargs, choices: Choices, render_mode: str | None, *, strict: bool
) -> tuple[gym.Env, list[str | None]]:
    """The env, and per choice None (applied) or the reason it was skipped."""
    check_chain_length(len(choices))
    reasons: list[str | None] = [None] * len(choices)
    planned: list[tuple[int, WrapperChoice, WrapperSpec, dict[str, Any]]] = []
    for index, choice in enumerate(choices):
        try:
            spec = get_spec(choice.name)
            planned.append((index, choice, spec, spec.validate(choice.values())))
        except ValueError as error:
            if strict:
                raise
            reasons[index] = str(error)

    tui_gym.envs.register_envs()  # our ids exist even if `tui_gym` was imported oddly
    try:
        env = gym.make(env_id, render_mode=render_mode, **(env_kwargs or {}))
    except (gym.error.UnregisteredEnv, gym.error.DeprecatedEnv) as error:  # e.g. Taxi-v3
        raise UnknownEnvError(env_id) from error

    for index, choice, spec, values in planned:
        reason = spec.fits(env, values)
        if reason is None:
            try:
                env = spec.factory(env, **values)
                continue
            except (ValueError, TypeError, NotImplementedError, gym.error.Error) as error:
                reason = f"{spec.name} could not wrap {env_label(env)}: {error}"
        if strict:
            env.close()
            raise WrapperMismatchError(reason, choice)
        reasons[index] = reason
    return env, reasons


def build_env(
    env_id: str, env_kwargs: Kwargs = None, choices: Choices = (), render_mode: str | None = None
) -> gym.Env:
    """`gym.make(env_id, render_mode=..., **env_kwargs)` wrapped by `choices`, first innermost
    (`UnknownEnvError`, `UnknownWrapperError`, `ValueError`, `WrapperMismatchError`)."""
    env, _ = _assemble(env_id, env_kwargs, choices, render_mode, strict=True)
    return env


def build_env_lenient(
    env_id: str, env_kwargs: Kwargs = None, choices: Choices = (), render_mode: str | None = None
) -> tuple[gym.Env, list[tuple[WrapperChoice, str]]]:
    """Like `build_env`, but skips the choices that do not fit (or are invalid): the env
    and the skipped choices, each with the reason."""
    env, reasons = _assemble(env_id, env_kwargs, choices, render_mode, strict=False)
    return env, [(c, r) for c, r in zip(choices, reasons, strict=True) if r is not None]


def check_choices(
    env_id: str, env_kwargs: Kwargs = None, choices: Choices = ()
) -> list[tuple[WrapperChoice, str | None]]:
    """For each choice, None if it would apply, else why not (as `build_env_lenient`)."""
    env, reasons = _assemble(env_id, env_kwargs, choices, None, strict=False)
    env.close()
    return list(zip(choices, reasons, strict=True))
