"""GridWorld, many grids at once: `tui_gym/GridWorld-v0` on numpy arrays.

`BatchedGridWorld` keeps `num_envs` (agent, target) placements in one array
and moves any subset of them in one call, with the scalar env's rules
(`tui_gym.envs.gridworld.GridWorldEnv`): moves 0 right (+x), 1 up (+y),
2 left (-x), 3 down (-y), positions clipped at the walls, `+reward_scale` on
reaching the target (the episode terminates) and `-step_penalty` on any other
step, the agent and target placed uniformly at random on different cells,
and the registered `TimeLimit` (`max_episode_steps`, 300 by default) turning
into truncation.

Observations are rows `(agent_x, agent_y, target_x, target_y)`, the flat form
of the env's `Dict(agent=Box(2), target=Box(2))` in space order. The random
stream is not the scalar env's, so starts match it in distribution, not draw
for draw; given the same placement, every step is identical. With `walls`,
a move into a wall stays put and placements are drawn among the free cells.
"""

from __future__ import annotations

import math

import numpy as np

from tui_gym.core.vector.base import (
    BatchStep,
    Selection,
    after_step,
    check_actions,
    check_num_envs,
    selection_size,
)
from tui_gym.envs.gridworld import ACTION_DELTAS
from tui_gym.envs.walls import cell_distances, check_walls, free_cells

__all__ = ["BatchedGridWorld"]

_DELTAS = np.array(ACTION_DELTAS, dtype=np.int64)
_DELTAS.setflags(write=False)


class BatchedGridWorld:
    """`num_envs` independent GridWorlds of one size, stepped together.

    `state` is the public (num_envs, 4) int64 array of `(ax, ay, tx, ty)`;
    `elapsed` counts each episode's steps for the time limit.

    Args:
        num_envs: how many grids.
        size: cells per side, an integer >= 2.
        reward_scale: reward for reaching the target.
        step_penalty: cost of every other step, >= 0.
        max_episode_steps: truncate after this many steps; None for never
            (the registered ids use 300).
        seed: seeds placements; the same seed gives the same starts.
        walls: cells (x, y) that cannot be entered.
    """

    n_actions = 4
    obs_width = 4

    def __init__(
        self,
        num_envs: int,
        size: int = 5,
        reward_scale: float = 1.0,
        step_penalty: float = 0.0,
        max_episode_steps: int | None = 300,
        seed: int | np.random.SeedSequence | None = None,
        walls: tuple[tuple[int, int], ...] = (),
    ) -> None:
        self.num_envs = check_num_envs(num_envs)
        if isinstance(size, bool) or not isinstance(size, int | np.integer) or size < 2:
            raise ValueError(f"GridWorld size must be an integer >= 2, got {size!r}")
        if not math.isfinite(reward_scale):
            raise ValueError(f"GridWorld reward_scale must be finite, got {reward_scale!r}")
        if not math.isfinite(step_penalty) or step_penalty < 0:
            raise ValueError(
                f"GridWorld step_penalty must be finite and >= 0, got {step_penalty!r}"
            )
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be >= 1, got {max_episode_steps}")
        self.size = int(size)
        self.reward_scale = float(reward_scale)
        # As in the env: `0.0 - penalty`, so no penalty gives 0.0 and not -0.0.
        self._miss_reward = 0.0 - float(step_penalty)
        self.step_penalty = float(step_penalty)
        self.max_episode_steps = max_episode_steps
        self.rng = np.random.default_rng(seed)
        self.walls = check_walls(self.size, walls)
        self._free = np.flatnonzero(free_cells(self.size, self.walls))  # free cell numbers
        self._distance = cell_distances(self.size, self.walls) if self.walls else None
        self.state = np.zeros((self.num_envs, 4), dtype=np.int64)
        self.state[:, 2] = 1  # a valid placement (agent != target) before the first reset
        self.elapsed = np.zeros(self.num_envs, dtype=np.int64)

    def observations(self, index: Selection = None) -> np.ndarray:
        """The current observation of each selected env: (k, 4) int64 rows (a copy)."""
        return np.array(self.state if index is None else self.state[index])

    def distances(self, index: Selection = None) -> np.ndarray:
        """Manhattan distance from agent to target, the env's `info["distance"]`."""
        rows = self.state if index is None else self.state[index]
        return self._distances(rows)

    def _distances(self, rows: np.ndarray) -> np.ndarray:
        if self._distance is None:
            return np.abs(rows[:, :2] - rows[:, 2:]).sum(axis=1)
        size = self.size
        return self._distance[rows[:, 0] * size + rows[:, 1], rows[:, 2] * size + rows[:, 3]]

    def reset(self, index: Selection = None) -> np.ndarray:
        """New placements for the selected envs (all by default); returns their observations.

        The agent's cell is uniform over the grid and the target's uniform over
        the other cells: the distribution of the env's draw-until-different.
        """
        k = selection_size(index, self.num_envs)
        cells = len(self._free)
        agent = self.rng.integers(0, cells, size=k)
        target = self.rng.integers(0, cells - 1, size=k)
        target += target >= agent  # skip the agent's cell
        agent, target = self._free[agent], self._free[target]
        rows = np.empty((k, 4), dtype=np.int64)
        rows[:, 0], rows[:, 1] = np.divmod(agent, self.size)
        rows[:, 2], rows[:, 3] = np.divmod(target, self.size)
        if index is None:
            self.state[:] = rows
            self.elapsed[:] = 0
        else:
            self.state[index] = rows
            self.elapsed[index] = 0
        return rows

    def step(
        self, actions: np.ndarray, index: Selection = None, *, autoreset: bool = True
    ) -> BatchStep:
        """Move the agent of each selected env (0 right, 1 up, 2 left, 3 down).

        With `autoreset`, envs whose episode ends get a new placement at once:
        `BatchStep.next_obs` still shows how the episode ended and
        `BatchStep.obs` the new start.
        """
        k = selection_size(index, self.num_envs)
        acts = check_actions(actions, k, self.n_actions)
        rows = np.array(self.state if index is None else self.state[index])
        before = rows[:, :2].copy() if self.walls else None
        np.clip(rows[:, :2] + _DELTAS[acts], 0, self.size - 1, out=rows[:, :2])
        if before is not None:  # a move into a wall stays put
            blocked = ~free_cells(self.size, self.walls)[rows[:, 0] * self.size + rows[:, 1]]
            rows[blocked, :2] = before[blocked]
        terminated = (rows[:, 0] == rows[:, 2]) & (rows[:, 1] == rows[:, 3])
        reward = np.where(terminated, self.reward_scale, self._miss_reward)
        if index is None:
            self.state[:] = rows
            self.elapsed += 1
            elapsed = self.elapsed
        else:
            self.state[index] = rows
            elapsed = self.elapsed[index] + 1
            self.elapsed[index] = elapsed
        distance = self._distances(rows)
        truncated, obs = after_step(rows, terminated, elapsed, self.max_episode_steps,
                                    index, self.reset, autoreset)
        return BatchStep(rows, reward, terminated, truncated, obs, {"distance": distance})
