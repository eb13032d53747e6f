"""tui-gym: a terminal playground for reinforcement learning.

Importing the package registers its own Gymnasium environments (see
`tui_gym.envs`).
"""

from tui_gym.envs import register_envs

__version__ = "0.1.0"

register_envs()

__all__ = ["__version__", "register_envs"]
