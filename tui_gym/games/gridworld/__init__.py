"""GridWorld: the game (`game`), and its exact model and shortest-path figures (`paths`); the
env itself is `tui_gym.envs.gridworld`."""

from tui_gym.games.gridworld.game import GridWorldGame

__all__ = ["GridWorldGame"]
