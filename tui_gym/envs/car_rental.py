"""`CarRentalEnv`: Sutton & Barto's Example 4.2, Jack's car rental (and Exercise 4.7's variant)."""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp.model import FiniteMDP
from tui_gym.envs.table_env import TableEnv

__all__ = ["ACTION_NAMES", "MAX_CARS", "MAX_MOVE", "MOVES", "CarRentalEnv", "car_rental_model",
           "nights"]

MAX_CARS = 20  # at each site; more are sent back to the company
MAX_MOVE = 5  # cars moved overnight, either way
MOVES = tuple(range(-MAX_MOVE, MAX_MOVE + 1))  # action a moves MOVES[a] cars, first to second
ACTION_NAMES = tuple("0" if move == 0 else f"{move:+d}" for move in MOVES)
RENT = 10.0  # dollars a car rented
MOVE_COST = 2.0  # dollars a car moved
PARKING, PARKED = 4.0, 10  # Exercise 4.7: dollars for a site keeping more than 10 cars
REQUESTS = (3.0, 4.0)  # Poisson means, first and second site
RETURNS = (3.0, 2.0)
SIDE = MAX_CARS + 1
FloatArray = npt.NDArray[np.float64]


def nights(first: np.ndarray, second: np.ndarray, move: np.ndarray,
           exercise: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, FloatArray]:
    """The cars moved (at most those there), each site's cars in the morning, and the
    night's cost (moves, and with `exercise` one free move to the second site and
    parking over 10 cars), broadcast over arrays of cars and moves."""
    moved = np.where(move >= 0, np.minimum(move, first), -np.minimum(-move, second))
    at_first = np.minimum(MAX_CARS, first - moved)
    at_second = np.minimum(MAX_CARS, second + moved)
    paid = np.abs(moved) - (exercise & (moved > 0))
    cost = MOVE_COST * paid
    if exercise:
        cost = cost + PARKING * ((at_first > PARKED).astype(int) + (at_second > PARKED))
    return moved, at_first, at_second, cost.astype(np.float64)


def _poisson(mean: float) -> FloatArray:
    """P(k) for k = 0 .. SIDE - 1, and P(k >= SIDE) as the last entry."""
    pmf = np.array([math.exp(-mean) * mean**k / math.factorial(k) for k in range(SIDE)])
    return np.append(pmf, max(0.0, 1.0 - pmf.sum()))


def _site(request: float, ret: float) -> tuple[FloatArray, FloatArray]:
    """`[m, n]` twice: the chance that a site with `m` cars in the morning has `n` at night,
    and the rentals expected given that it does."""
    asked, back = _poisson(request), _poisson(ret)
    chance = np.zeros((SIDE, SIDE))
    rented = np.zeros((SIDE, SIDE))
    for m in range(SIDE):
        for k, p_ask in enumerate(asked):  # k = SIDE stands for "SIDE or more": all rented
            rent = min(k, m)
            for j, p_back in enumerate(back):
                n = min(MAX_CARS, m - rent + j)
                chance[m, n] += p_ask * p_back
                rented[m, n] += p_ask * p_back * rent
    with np.errstate(invalid="ignore", divide="ignore"):
        return chance, np.where(chance > 0, rented / chance, 0.0)


@lru_cache(maxsize=2)
def car_rental_model(exercise: bool = False) -> FiniteMDP:
    """(Kept.) The exact transitions: states `first * 21 + second`, actions `MOVES`, every next
    state an outcome (its reward: the rentals expected given it, less the night's costs).
    Episodes start uniformly on every state."""
    n = SIDE * SIDE
    first_site, second_site = _site(REQUESTS[0], RETURNS[0]), _site(REQUESTS[1], RETURNS[1])
    first, second = np.divmod(np.arange(n), SIDE)
    _, at_first, at_second, cost = nights(first[:, None], second[:, None],
                                          np.array(MOVES)[None, :], exercise)
    prob = first_site[0][at_first][..., :, None] * second_site[0][at_second][..., None, :]
    rented = first_site[1][at_first][..., :, None] + second_site[1][at_second][..., None, :]
    reward = RENT * rented - cost[..., None, None]
    shape = (n, len(MOVES), n)
    next_state = np.broadcast_to(np.arange(n), shape).copy()
    return FiniteMDP(next_state, prob.reshape(shape), reward.reshape(shape),
                     np.zeros(shape, dtype=bool), np.full(n, 1.0 / n), action_names=ACTION_NAMES)


class CarRentalEnv(TableEnv):
    """Sutton & Barto's Example 4.2: Jack moves cars between his two sites overnight.

    ## Action Space
    The cars moved from the first site to the second, -5 to +5 (action `a` moves
    `a - 5`), at most those the site has.

    ## Observation Space
    The cars at each site at the end of the day, `first * 21 + second`.

    ## Rewards
    $10 a car rented, less $2 a car moved. Requests are Poisson (means 3 and 4),
    returns too (3 and 2), back the next day; a site holds at most 20 cars. With
    `exercise` (Exercise 4.7) one move to the second site is free, and a site keeping
    more than 10 cars overnight costs $4.

    ## Starting State
    Any number of cars at each site, uniformly.

    ## Episode End
    Never: the task is continuing (the game limits an episode).

    ## Arguments
    `exercise` (False), `render_mode` "ansi".
    """

    action_names = ACTION_NAMES

    def __init__(self, exercise: bool = False, render_mode: str | None = None) -> None:
        self.exercise = bool(exercise)
        self.last_day: dict[str, Any] = {}
        super().__init__(car_rental_model(self.exercise), render_mode)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, Any]]:
        gym.Env.reset(self, seed=seed)  # a uniform start, drawn as an integer
        self.s = int(self.np_random.integers(SIDE * SIDE))
        self.lastaction = None
        self.last_day = {}
        return self.s, {}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, Any]]:
        """The night's move, then each site's requests and returns drawn (Poisson)."""
        state, action = self.started(), self.checked(action)
        first, second = divmod(state, SIDE)
        night = nights(np.asarray(first), np.asarray(second), np.asarray(MOVES[action]),
                       self.exercise)
        moved, morning, cost = int(night[0]), [int(n) for n in night[1:3]], float(night[3])
        rng = self.np_random
        asked = [int(rng.poisson(mean)) for mean in REQUESTS]
        back = [int(rng.poisson(mean)) for mean in RETURNS]
        rented = [min(k, m) for k, m in zip(asked, morning, strict=True)]
        cars = [min(MAX_CARS, m - r + b) for m, r, b in zip(morning, rented, back, strict=True)]
        self.s = cars[0] * SIDE + cars[1]
        self.lastaction = action
        self.last_day = {"moved": moved, "cost": cost, "requested": asked, "rented": rented,
                         "returned": back}
        return self.s, RENT * sum(rented) - cost, False, False, dict(self.last_day)

    def picture(self) -> str:
        if self.s is None:
            return ""
        first, second = divmod(self.s, SIDE)
        text = f"first site {first} cars, second site {second} cars\n"
        day = self.last_day
        if day:
            text = (f"  (moved {day['moved']:+d}, rented {day['rented'][0]}+{day['rented'][1]},"
                    f" returned {day['returned'][0]}+{day['returned'][1]})\n") + text
        return text
