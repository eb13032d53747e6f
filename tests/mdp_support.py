"""Shared by the finite-MDP tests: small models, and returns sampled by playing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from tui_gym.core.mdp import FiniteMDP, policy_matrix


def random_model(
    rng: np.random.Generator,
    n_states: int = 6,
    n_actions: int = 3,
    outcomes: int = 3,
    horizon: int | None = None,
    end_chance: float = 0.3,
) -> FiniteMDP:
    """A random MDP: every pair has `outcomes` outcomes, some terminal, rewards in [-1, 1]."""
    shape = (n_states, n_actions, outcomes)
    prob = rng.dirichlet(np.ones(outcomes), size=(n_states, n_actions))
    initial = rng.dirichlet(np.ones(n_states))
    return FiniteMDP(
        next_state=rng.integers(0, n_states, size=shape),
        prob=prob,
        reward=rng.uniform(-1, 1, size=shape),
        terminal=rng.random(shape) < end_chance,
        initial=initial,
        horizon=horizon,
    )


def sampled_returns(
    model: FiniteMDP,
    policy: np.ndarray,
    episodes: int,
    rng: np.random.Generator,
    gamma: float = 1.0,
    max_steps: int | None = None,
) -> np.ndarray:
    """Returns of `episodes` episodes played at once, drawn from the model's cumulative
    probabilities with numpy (a check of the model apart from the engine's sampler)."""
    matrix = policy_matrix(model, policy)
    cumulative = np.cumsum(matrix, axis=1)
    starts = np.cumsum(model.initial)
    states = np.minimum(np.searchsorted(starts, rng.random(episodes), side="right"),
                        model.n_states - 1)
    totals = np.zeros(episodes)
    alive = np.ones(episodes, dtype=bool)
    limit = model.horizon if model.horizon is not None else max_steps
    assert limit is not None, "an episode limit or max_steps is needed to stop"
    for t in range(limit):
        rows = np.flatnonzero(alive)
        if rows.size == 0:
            break
        actions = (rng.random(rows.size)[:, None] >= cumulative[states[rows]]).sum(axis=1)
        actions = np.minimum(actions, model.n_actions - 1)
        pairs = model.cumulative[states[rows], actions]
        outcome = (rng.random(rows.size)[:, None] >= pairs).sum(axis=1)
        outcome = np.minimum(outcome, model.max_outcomes - 1)
        at = (states[rows], actions, outcome)
        totals[rows] += gamma**t * model.reward[at]
        states[rows] = model.next_state[at]
        alive[rows[model.terminal[at]]] = False
    return totals


def env_returns(env: gym.Env, policy: np.ndarray, episodes: int, seed: int) -> np.ndarray:
    """Returns of `episodes` episodes of a deterministic `[S]` policy played on the real env."""
    totals = np.zeros(episodes)
    for episode in range(episodes):
        state, _ = env.reset(seed=seed if episode == 0 else None)
        while True:
            state, reward, terminated, truncated, _ = env.step(int(policy[state]))
            totals[episode] += float(reward)
            if terminated or truncated:
                break
    return totals


def within_standard_errors(samples: np.ndarray, exact: float, errors: float = 4.0) -> bool:
    """Whether the samples' mean is within `errors` standard errors of `exact`."""
    error = samples.std(ddof=1) / np.sqrt(len(samples))
    return abs(samples.mean() - exact) <= errors * error + 1e-12
