"""GridWorld: Gymnasium's quick-start custom environment, made correct; its walls, moves and
shortest distances."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence
from functools import lru_cache
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces
from gymnasium.error import ResetNeeded
from numpy.typing import NDArray

__all__ = [
    "ACTION_DELTAS", "ACTION_NAMES", "AGENT_COLOR", "BACKGROUND_COLOR", "CELL_PIXELS",
    "GRID_LINE_COLOR", "TARGET_COLOR", "WALL_COLOR", "GridWorldEnv", "Walls", "cell_distances",
    "cell_moves", "check_walls", "free_cells",
]

Position = tuple[int, int]
Walls = tuple[tuple[int, int], ...]
IntArray = npt.NDArray[np.int64]
ObsType = dict[str, NDArray[np.int64]]

# The tutorial's mapping: x grows to the right, y grows upwards.
ACTION_NAMES: tuple[str, ...] = ("right", "up", "left", "down")
ACTION_DELTAS: tuple[Position, ...] = ((1, 0), (0, 1), (-1, 0), (0, -1))

# rgb_array drawing: each cell is CELL_PIXELS square, with a one-pixel grid line
# on every cell boundary (the image is size * CELL_PIXELS + 1 pixels a side).
CELL_PIXELS = 32
BACKGROUND_COLOR: tuple[int, int, int] = (255, 255, 255)
GRID_LINE_COLOR: tuple[int, int, int] = (190, 190, 190)
AGENT_COLOR: tuple[int, int, int] = (40, 90, 220)
TARGET_COLOR: tuple[int, int, int] = (220, 40, 40)
WALL_COLOR: tuple[int, int, int] = (70, 72, 80)

_RENDER_MODES: tuple[str | None, ...] = (None, "ansi", "human", "rgb_array")


def _is_a(kind: type, value: object) -> bool:
    return isinstance(value, kind) and not isinstance(value, bool | np.bool_)


def _finite(name: str, value: Any, minimum: float | None = None) -> float:
    """`value` as a float; ValueError naming `name` unless a finite real number >= `minimum`."""
    if (not _is_a(numbers.Real, value) or not math.isfinite(value)
            or (minimum is not None and value < minimum)):
        bound = "" if minimum is None else f" >= {minimum:g}"
        raise ValueError(f"GridWorld {name} must be a finite number{bound}, got {value!r}")
    return float(value)


def check_walls(size: int, walls: Iterable[Any] | None) -> Walls:
    """The walls as sorted `(x, y)` pairs without repeats; `ValueError` for a cell off the
    grid, a pair that is not two integers, or walls that leave fewer than two free cells."""
    out: set[tuple[int, int]] = set()
    for wall in walls or ():
        array = np.asarray(wall)
        if array.shape != (2,) or not np.issubdtype(array.dtype, np.integer):
            raise ValueError(f"a GridWorld wall must be two integers (x, y), got {wall!r}")
        x, y = int(array[0]), int(array[1])
        if not (0 <= x < size and 0 <= y < size):
            raise ValueError(f"wall ({x}, {y}) is off the {size}x{size} grid")
        out.add((x, y))
    if size * size - len(out) < 2:
        raise ValueError(f"walls leave {size * size - len(out)} free cell(s); the agent and "
                         "the target need two")
    return tuple(sorted(out))


def free_cells(size: int, walls: Walls) -> npt.NDArray[np.bool_]:
    """`[cells]`: whether each cell is free (not a wall)."""
    free = np.ones(size * size, dtype=bool)
    for x, y in walls:
        free[x * size + y] = False
    return free


@lru_cache(maxsize=16)
def cell_moves(size: int, walls: Walls = ()) -> IntArray:
    """`[4, cells]`: where each action leads from each cell (blocked moves stay put)."""
    cells = size * size
    x, y = np.divmod(np.arange(cells), size)
    free = free_cells(size, walls)
    moves = np.empty((4, cells), dtype=np.int64)
    for a, (dx, dy) in enumerate(ACTION_DELTAS):
        to = np.clip(x + dx, 0, size - 1) * size + np.clip(y + dy, 0, size - 1)
        moves[a] = np.where(free[to], to, np.arange(cells))
    moves.setflags(write=False)
    return moves


@lru_cache(maxsize=16)
def cell_distances(size: int, walls: Walls = ()) -> IntArray:
    """`[cells, cells]`: the fewest moves from a cell (row) to a cell (column); -1 where
    there is no way (either is a wall, or walls part them)."""
    cells = size * size
    free = free_cells(size, walls)
    if not walls:
        x, y = np.divmod(np.arange(cells), size)
        distance = np.abs(x[:, None] - x[None, :]) + np.abs(y[:, None] - y[None, :])
        distance = distance.astype(np.int64)
        distance.setflags(write=False)
        return distance
    moves = cell_moves(size, walls)
    distance = np.full((cells, cells), -1, dtype=np.int64)
    frontier = np.diag(free)  # [cell, target]: at the distance of the last round
    distance[frontier] = 0
    step = 0
    while frontier.any():
        step += 1
        reached = frontier[moves[0]] | frontier[moves[1]] | frontier[moves[2]] | frontier[moves[3]]
        frontier = reached & (distance < 0) & free[:, None]
        distance[frontier] = step
    distance.setflags(write=False)
    return distance


class GridWorldEnv(gym.Env[ObsType, int]):
    """An agent walks a square grid to reach a target: Gymnasium's "Create a custom
    environment" tutorial, with fresh observation arrays and optional walls.

    ## Action Space
    `Discrete(4)`: 0 right (`x + 1`), 1 up (`y + 1`), 2 left, 3 down; a move off the
    grid or into a wall leaves the agent where it was.

    ## Observation Space
    `{"agent": (x, y), "target": (x, y)}`, `np.int64` arrays; `info["distance"]` is
    the fewest moves between them (-1 when walls leave no way).

    ## Rewards
    `+reward_scale` for reaching the target, `-step_penalty` for any other step.

    ## Starting State
    The agent, then the target on another free cell, at random; either may be placed
    with `reset(options={"agent": (x, y), "target": (x, y)})`.

    ## Episode End
    Terminated on the target; the registered ids truncate after 300 steps.

    ## Arguments
    `render_mode` (None, "ansi", "human" or "rgb_array"), `size=5` (>= 2),
    `reward_scale=1.0`, `step_penalty=0.0` (>= 0), `walls=()` ((x, y) cells).
    """

    metadata: dict[str, Any] = {"render_modes": ["ansi", "human", "rgb_array"], "render_fps": 4}
    reports_distance = True  # every step's info holds "distance" (DistanceShaping reads it)

    def __init__(
        self, render_mode: str | None = None, size: int = 5, reward_scale: float = 1.0,
        step_penalty: float = 0.0, walls: Sequence[Sequence[int]] = (),
    ) -> None:
        if not _is_a(numbers.Integral, size) or size < 2:
            raise ValueError(f"GridWorld size must be an integer >= 2, got {size!r}")
        self.reward_scale = _finite("reward_scale", reward_scale)
        self.step_penalty = _finite("step_penalty", step_penalty, minimum=0)
        if render_mode not in _RENDER_MODES:
            valid = ", ".join(repr(mode) for mode in _RENDER_MODES)
            raise ValueError(f"GridWorld render_mode must be one of {valid}, got {render_mode!r}")

        self.size = int(size)
        self.walls: Walls = check_walls(self.size, walls)
        self._wall_set = frozenset(self.walls)
        self._moves = cell_moves(self.size, self.walls).tolist()  # plain ints: quick to index
        self.render_mode = render_mode
        self.observation_space = spaces.Dict(  # type: ignore[assignment]
            {key: spaces.Box(0, self.size - 1, shape=(2,), dtype=np.int64)
             for key in ("agent", "target")})
        self.action_space = spaces.Discrete(len(ACTION_NAMES))  # type: ignore[assignment]

        # Positions are kept as tuples of Python ints, so nothing returned to a
        # caller can alias the environment's state.
        self._agent: Position | None = None
        self._target: Position | None = None
        self._background: NDArray[np.uint8] | None = None

    # -- state -------------------------------------------------------------

    @property
    def agent_position(self) -> Position:
        """The agent's `(x, y)`; raises `ResetNeeded` before the first reset."""
        return self._require_state()[0]

    @property
    def target_position(self) -> Position:
        """The target's `(x, y)`; raises `ResetNeeded` before the first reset."""
        return self._require_state()[1]

    def _require_state(self) -> tuple[Position, Position]:
        if self._agent is None or self._target is None:
            raise ResetNeeded("GridWorld: call reset() before step() or render()")
        return self._agent, self._target

    def _get_obs(self) -> ObsType:
        agent, target = self._require_state()
        return {"agent": np.array(agent, dtype=np.int64), "target": np.array(target, np.int64)}

    def _get_info(self) -> dict[str, Any]:
        (ax, ay), (tx, ty) = self._require_state()
        table = cell_distances(self.size, self.walls)
        return {"distance": int(table[ax * self.size + ay, tx * self.size + ty])}

    def _random_position(self) -> Position:
        # The tutorial's draw, repeated while it lands on a wall (none without walls, so
        # a grid without walls draws exactly as the tutorial's does).
        while True:
            x, y = self.np_random.integers(0, self.size, size=2, dtype=np.int64)
            if (int(x), int(y)) not in self._wall_set:
                return int(x), int(y)

    def _option_position(self, options: dict[str, Any], key: str) -> Position | None:
        value = options.get(key)
        if value is None:
            return None
        array = np.asarray(value)
        two_ints = array.shape == (2,) and np.issubdtype(array.dtype, np.integer)
        if not two_ints or np.any(array < 0) or np.any(array >= self.size):
            raise ValueError(f"GridWorld reset option {key!r} must be two integers (x, y) in "
                             f"[0, {self.size - 1}], got {value!r}")
        position = int(array[0]), int(array[1])
        if position in self._wall_set:
            raise ValueError(f"GridWorld reset option {key!r} puts it on the wall {position}")
        return position

    # -- gymnasium API -----------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        super().reset(seed=seed)
        options = {} if options is None else options
        if unknown := sorted(set(options) - {"agent", "target"}):
            raise ValueError(f"GridWorld reset options accept 'agent' and 'target', "
                             f"got {unknown!r}")
        agent = self._option_position(options, "agent")
        target = self._option_position(options, "target")
        if agent is not None and agent == target:
            raise ValueError(f"GridWorld reset options put the agent and the target on the same "
                             f"cell {agent}; they must differ")

        # The tutorial's order: the agent first, then resample the target until
        # it differs (uniform over the other cells).
        if agent is None:
            agent = self._random_position()
            while agent == target:
                agent = self._random_position()
        while target is None or target == agent:
            target = self._random_position()

        self._agent, self._target = agent, target
        if self.render_mode == "human":
            self.render()
        return self._get_obs(), self._get_info()

    def step(self, action: int) -> tuple[ObsType, float, bool, bool, dict[str, Any]]:
        agent, target = self._require_state()
        if not self.action_space.contains(action):
            raise ValueError(f"GridWorld action must be an integer in [0, {len(ACTION_NAMES) - 1}] "
                             f"{ACTION_NAMES}, got {action!r}")
        self._agent = divmod(self._moves[int(action)][agent[0] * self.size + agent[1]], self.size)

        terminated = self._agent == target
        # `0.0 - penalty` rather than `-penalty`, so no penalty gives 0.0 and not -0.0.
        reward = self.reward_scale if terminated else 0.0 - self.step_penalty
        if self.render_mode == "human":
            self.render()
        return self._get_obs(), reward, terminated, False, self._get_info()

    def render(self) -> str | NDArray[np.uint8] | None:
        if self.render_mode is None:
            env_id = self.spec.id if self.spec is not None else "tui_gym/GridWorld-v0"
            gym.logger.warn(
                "You are calling render method without specifying any render mode. "
                "You can specify the render_mode at initialization, "
                f'e.g. gym.make("{env_id}", render_mode="rgb_array")'
            )
            return None
        if self.render_mode == "ansi":
            return self._render_text()
        if self.render_mode == "human":
            print(self._render_text(), flush=True)
            return None
        return self._render_rgb()

    def close(self) -> None:
        self._background = None

    # -- drawing -----------------------------------------------------------

    def _render_text(self) -> str:
        agent, target = self._require_state()
        border = "+" + "-" * (2 * self.size + 1) + "+"

        def mark(cell: Position) -> str:
            if cell == agent:
                return "*" if agent == target else "A"
            return "T" if cell == target else "#" if cell in self._wall_set else "."

        rows = ["| " + " ".join(mark((x, y)) for x in range(self.size)) + " |"
                for y in range(self.size - 1, -1, -1)]
        return "\n".join([border, *rows, border])

    def _cell_origin(self, position: Sequence[int]) -> tuple[int, int]:
        """Top-left pixel (row, col) inside the cell at `position`; y grows upwards."""
        x, y = position
        return (self.size - 1 - y) * CELL_PIXELS + 1, x * CELL_PIXELS + 1

    def _grid_image(self) -> NDArray[np.uint8]:
        if self._background is None:
            side = self.size * CELL_PIXELS + 1
            image = np.empty((side, side, 3), dtype=np.uint8)
            image[:] = BACKGROUND_COLOR
            image[::CELL_PIXELS, :] = GRID_LINE_COLOR
            image[:, ::CELL_PIXELS] = GRID_LINE_COLOR
            for wall in self.walls:
                row, col = self._cell_origin(wall)
                image[row : row + CELL_PIXELS - 1, col : col + CELL_PIXELS - 1] = WALL_COLOR
            self._background = image
        return self._background.copy()

    def _render_rgb(self) -> NDArray[np.uint8]:
        agent, target = self._require_state()
        image = self._grid_image()
        inner = CELL_PIXELS - 1  # pixels inside a cell, between its grid lines

        margin = inner // 6
        row, col = self._cell_origin(target)
        image[row + margin : row + inner - margin, col + margin : col + inner - margin] = (
            TARGET_COLOR
        )

        # The agent is drawn last, so on the target it shows as a disc on red.
        row, col = self._cell_origin(agent)
        centre = (inner - 1) / 2
        yy, xx = np.mgrid[0:inner, 0:inner]
        disc = (yy - centre) ** 2 + (xx - centre) ** 2 <= (0.36 * inner) ** 2
        image[row : row + inner, col : col + inner][disc] = AGENT_COLOR
        return image
