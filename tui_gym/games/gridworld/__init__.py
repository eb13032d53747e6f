"""GridWorld: the game (`game`), its shortest-path figures (`paths`) and its exact
model (`model`); the env itself is `tui_gym.envs.gridworld`."""

from tui_gym.games.gridworld.game import GridWorldGame

__all__ = ["GridWorldGame"]
