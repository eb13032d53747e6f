"""Gymnasium environments of our own, and their registration.

`register_envs()` registers GridWorld as `tui_gym/GridWorld-v0` and under the
tutorial's id `gymnasium_env/GridWorld-v0` (both with `max_episode_steps=300`).
It is idempotent and runs on `import tui_gym`.
"""

from __future__ import annotations

import gymnasium as gym

GRIDWORLD_IDS = ("tui_gym/GridWorld-v0", "gymnasium_env/GridWorld-v0")
GRIDWORLD_ENTRY_POINT = "tui_gym.envs.gridworld:GridWorldEnv"
GRIDWORLD_MAX_STEPS = 300


def register_envs() -> None:
    """Register our environments with Gymnasium (safe to call twice)."""
    for env_id in GRIDWORLD_IDS:
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point=GRIDWORLD_ENTRY_POINT,
                max_episode_steps=GRIDWORLD_MAX_STEPS,
            )
