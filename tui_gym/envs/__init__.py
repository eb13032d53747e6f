"""Gymnasium environments of our own, and their registration."""

from __future__ import annotations

import gymnasium as gym

GRIDWORLD_MAX_STEPS = 300
TILE_MAP_ID = "tui_gym/TileMap-v0"
# id -> (entry point, episode limit)
ENVS: dict[str, tuple[str, int | None]] = {
    "tui_gym/GridWorld-v0": ("tui_gym.envs.gridworld:GridWorldEnv", GRIDWORLD_MAX_STEPS),
    "gymnasium_env/GridWorld-v0": ("tui_gym.envs.gridworld:GridWorldEnv", GRIDWORLD_MAX_STEPS),
    TILE_MAP_ID: ("tui_gym.envs.tile_map:TileMapEnv", None),
    "tui_gym/ABGrid-v0": ("tui_gym.envs.dp_grid:ABGridEnv", 50),
    "tui_gym/CornerGrid-v0": ("tui_gym.envs.dp_grid:CornerGridEnv", 100),
    "tui_gym/Gambler-v0": ("tui_gym.envs.gambler:GamblerEnv", 1000),
    "tui_gym/CarRental-v0": ("tui_gym.envs.car_rental:CarRentalEnv", 20),
    "tui_gym/RandomWalk-v0": ("tui_gym.envs.dp_grid:RandomWalkEnv", 1000),
    "tui_gym/WindyGridWorld-v0": ("tui_gym.envs.dp_grid:WindyGridWorldEnv", 2000),
    "tui_gym/WindyGridWorldKing-v0": ("tui_gym.envs.dp_grid:KingWindyGridWorldEnv", 2000),
    "tui_gym/DynaMaze-v0": ("tui_gym.envs.dyna_maze:DynaMazeEnv", 5000),
    "tui_gym/BlockingMaze-v0": ("tui_gym.envs.dyna_maze:BlockingMazeEnv", 5000),
    "tui_gym/ShortcutMaze-v0": ("tui_gym.envs.dyna_maze:ShortcutMazeEnv", 5000),
    "tui_gym/MaxBias-v0": ("tui_gym.envs.max_bias:MaxBiasEnv", 10),
}


def register_envs() -> None:
    """Register our environments with Gymnasium (safe to call twice)."""
    for env_id, (entry_point, limit) in ENVS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point=entry_point, max_episode_steps=limit)
