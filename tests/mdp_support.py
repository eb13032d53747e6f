"""Shared by the finite-MDP tests: small models, and returns sampled by playing."""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from tui_gym.core.mdp import BatchSampler, FiniteMDP, policy_matrix


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
    """Returns of `episodes` episodes played at once by the batched sampler."""
    matrix = policy_matrix(model, policy)
    cumulative = np.cumsum(matrix, axis=1)
    sampler = BatchSampler(model)
    states = sampler.reset(episodes, rng)
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
        step = sampler.step(states[rows], actions, rng)
        totals[rows] += gamma**t * step.reward
        states[rows] = step.next_state
        alive[rows[step.terminated]] = False
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
