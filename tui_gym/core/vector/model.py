"""Any finite game on numpy arrays: `BatchedModel`, a `FiniteMDP` stepped in batches.

`BatchedModel` keeps the state of `num_envs` episodes of one model and steps
any subset of them as `tui_gym.core.mdp.BatchSampler` does (one uniform draw
per row against the row's cumulative probabilities, no loop over rows; none
at all for a model whose every move has one outcome), reading the model's
arrays flat so that one index serves every array. Observations are the model's state numbers, one
column wide, as a `Discrete` observation space reads them. Episodes follow
the model's own distributions, so they agree in distribution with the env the
model was read from, not draw for draw. `model_form(title, model)` is the
`BatchedForm` the vector engine builds it from.
"""

from __future__ import annotations

import numpy as np

from tui_gym.core.mdp import BatchSampler, FiniteMDP
from tui_gym.core.vector.base import (
    BatchedForm,
    BatchStep,
    Selection,
    after_step,
    check_actions,
    check_num_envs,
    selection_size,
)

__all__ = ["MODEL_NUM_ENVS", "BatchedModel", "model_form"]

MODEL_NUM_ENVS = 8192  # episodes a model game plays at once


class BatchedModel:
    """`num_envs` episodes of one finite MDP, stepped together.

    Args:
        model: the game's model (its own `horizon` is not used: the episode
            limit is `max_episode_steps`, read from the env's wrappers).
        num_envs: how many episodes at once.
        seed: seeds the starts and the transitions.
        max_episode_steps: truncate after this many steps; None for never.
    """

    obs_width = 1

    def __init__(
        self,
        model: FiniteMDP,
        num_envs: int,
        seed: int | np.random.SeedSequence | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        self.num_envs = check_num_envs(num_envs)
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be >= 1, got {max_episode_steps}")
        self.model = model
        self.n_actions = model.n_actions
        self.max_episode_steps = max_episode_steps
        self.sampler = BatchSampler(model)
        n_actions, outcomes = model.n_actions, model.max_outcomes
        self._outcomes = outcomes
        self._cumulative = model.cumulative.reshape(-1, outcomes)
        self._next = model.next_state.reshape(-1)
        self._reward = model.reward.reshape(-1)
        self._terminal = model.terminal.reshape(-1)
        self._rows = n_actions
        self.rng = np.random.default_rng(seed)
        self.state = np.zeros(self.num_envs, dtype=np.int64)
        self.elapsed = np.zeros(self.num_envs, dtype=np.int64)

    def observations(self, index: Selection = None) -> np.ndarray:
        """The current observation of each selected env: (k, 1) int64 rows (a copy)."""
        rows = self.state if index is None else self.state[index]
        return np.array(rows)[:, None]

    def reset(self, index: Selection = None) -> np.ndarray:
        """New episodes for the selected envs (all by default); returns their observations."""
        k = selection_size(index, self.num_envs)
        starts = self.sampler.reset(k, self.rng)
        if index is None:
            self.state[:] = starts
            self.elapsed[:] = 0
        else:
            self.state[index] = starts
            self.elapsed[index] = 0
        return starts[:, None]

    def step(
        self, actions: np.ndarray, index: Selection = None, *, autoreset: bool = True
    ) -> BatchStep:
        """One move of each selected env; with `autoreset`, ended episodes start again
        (`BatchStep.next_obs` still shows how they ended, `BatchStep.obs` the new start)."""
        k = selection_size(index, self.num_envs)
        acts = check_actions(actions, k, self.n_actions)
        states = self.state if index is None else self.state[index]
        pair = states * self._rows + acts  # the row of (state, action) in the flat arrays
        flat = pair * self._outcomes
        if self._outcomes > 1:
            # Outcome k is drawn when cumulative[k - 1] <= u < cumulative[k].
            draws = self.rng.random(len(pair))
            flat += (draws[:, None] >= self._cumulative[pair]).sum(axis=1)
        next_state = self._next[flat]
        terminated = self._terminal[flat]
        if index is None:
            self.state[:] = next_state
            self.elapsed += 1
            elapsed = self.elapsed
        else:
            self.state[index] = next_state
            elapsed = self.elapsed[index] + 1
            self.elapsed[index] = elapsed
        next_obs = next_state[:, None]
        truncated, obs = after_step(next_obs, terminated, elapsed,
                                    self.max_episode_steps, index, self.reset, autoreset)
        return BatchStep(next_obs, self._reward[flat], terminated, truncated, obs)


def model_form(title: str, model: FiniteMDP) -> BatchedForm:
    """The vector engine's recipe for a game played from its model."""

    def make(
        num_envs: int, seed: int | np.random.SeedSequence | None, max_episode_steps: int | None
    ) -> BatchedModel:
        return BatchedModel(model, num_envs, seed=seed, max_episode_steps=max_episode_steps)

    # Model steps are cheap: larger batches spread the per-batch work further.
    return BatchedForm(title, make, key=("model", id(model)), num_envs=MODEL_NUM_ENVS)
