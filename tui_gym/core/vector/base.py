"""What every batched environment shares: the result of one batched step, and its recipe.

A batched env holds the state of `num_envs` copies of one game in numpy
arrays and steps any subset of them at once (`BatchedEnv`). `BatchStep` is
what a step returns, one row per stepped env; `Selection` is how callers name
the subset (None for all of them, else an int array of env indices). A game
hands the vector engine a `BatchedForm`: its title, how to make its batched
env, and the per-step `info` entries it reports (e.g. "distance").
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

__all__ = [
    "BatchStep",
    "BatchedEnv",
    "BatchedForm",
    "Selection",
    "after_step",
    "check_actions",
    "check_num_envs",
    "selection_size",
]

Selection = np.ndarray | None
"""The envs a call applies to: None for all, else an int array of distinct env indices."""


@dataclass(frozen=True)
class BatchStep:
    """One batched step: row `i` belongs to the `i`-th stepped env.

    `next_obs` is the observation after the action; for an env whose episode
    just ended it is the final observation (the one to bootstrap from after a
    truncation). `obs` is what each env will act on next: `next_obs`, except
    that envs reset automatically show their new starting observation.
    `info` holds the per-step entries the game reports, one value per row
    (e.g. "distance", the scalar env's `info["distance"]` after the move).
    """

    next_obs: np.ndarray  # int64 (k, obs_width)
    reward: np.ndarray  # float64 (k,)
    terminated: np.ndarray  # bool (k,)
    truncated: np.ndarray  # bool (k,)
    obs: np.ndarray  # int64 (k, obs_width)
    info: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def done(self) -> np.ndarray:
        """Episodes that ended on this step (terminated or truncated)."""
        return self.terminated | self.truncated


class BatchedEnv(Protocol):
    """`num_envs` copies of one game in arrays; any subset stepped in one call."""

    num_envs: int
    n_actions: int
    obs_width: int

    def observations(self, index: Selection = None) -> np.ndarray: ...

    def reset(self, index: Selection = None) -> np.ndarray: ...

    def step(
        self, actions: np.ndarray, index: Selection = None, *, autoreset: bool = True
    ) -> BatchStep: ...


MakeBatched = Callable[[int, "int | np.random.SeedSequence | None", "int | None"], BatchedEnv]


@dataclass(frozen=True)
class BatchedForm:
    """A game's recipe for the vector engine.

    `make(num_envs, seed, max_episode_steps)` builds the batched env (the
    episode limit is read from the env's wrappers); `info` names the per-step
    entries its `BatchStep.info` carries; `key` tells two forms of one game
    apart (for equality); `num_envs` is how many episodes it plays best at
    once (None: the engine's default).
    """

    title: str
    make: MakeBatched = field(compare=False)
    info: tuple[str, ...] = ()
    key: Hashable = ()
    num_envs: int | None = None


def check_num_envs(num_envs: int) -> int:
    if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
        raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
    return int(num_envs)


def selection_size(index: Selection, num_envs: int) -> int:
    return num_envs if index is None else len(index)


def check_actions(actions: np.ndarray, expected: int, n_actions: int) -> np.ndarray:
    """The actions as an int64 array of `expected` values in `range(n_actions)`."""
    acts = np.asarray(actions)
    if acts.shape != (expected,):
        raise ValueError(f"expected {expected} actions, got an array of shape {acts.shape}")
    if not np.issubdtype(acts.dtype, np.integer):
        raise ValueError(f"actions must be integers, got dtype {acts.dtype}")
    if expected and (acts.min() < 0 or acts.max() >= n_actions):
        raise ValueError(f"actions must be in [0, {n_actions - 1}]")
    return acts.astype(np.int64, copy=False)


def after_step(
    next_obs: np.ndarray,
    terminated: np.ndarray,
    elapsed: np.ndarray,
    max_episode_steps: int | None,
    index: Selection,
    reset: Callable[[np.ndarray], np.ndarray],
    autoreset: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """What every batched game does after a move: truncation, then auto-reset.

    Returns `truncated` (episodes at the time limit) and `obs`: `next_obs`,
    with the new starting observation in place for envs that `reset` started
    again (only with `autoreset`).
    """
    if max_episode_steps is None:
        truncated = np.zeros(len(next_obs), dtype=bool)
    else:
        truncated = elapsed >= max_episode_steps
    obs = next_obs
    if autoreset:
        done = np.flatnonzero(terminated | truncated)
        if done.size:
            obs = next_obs.copy()
            envs = done if index is None else np.asarray(index)[done]
            obs[done] = reset(envs)
    return truncated, obs
