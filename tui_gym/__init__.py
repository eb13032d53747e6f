"""tui-gym: a terminal playground for reinforcement learning.

Importing the package registers its Gymnasium environments
(`tui_gym/GridWorld-v0` and the tutorial's id `gymnasium_env/GridWorld-v0`).
"""

from tui_gym.envs import register_envs

__version__ = "0.1.0"

register_envs()

__all__ = ["__version__", "register_envs"]
