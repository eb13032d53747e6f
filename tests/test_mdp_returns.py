"""`return_range`: the lowest and highest return one episode can have, read off a model, and
each game's oracle giving it for the game as its arguments and wrappers make it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tui_gym.core.mdp import FiniteMDP, return_range
from tui_gym.games import game_named
from tui_gym.session.returns import return_range_of


def chain(reward_loop: float, horizon: int | None) -> FiniteMDP:
    """Two states: from 0, action 0 ends the episode paying 1, action 1 stays in 0
    paying `reward_loop`."""
    next_state = np.array([[[1], [0]], [[1], [1]]])
    reward = np.array([[[1.0], [reward_loop]], [[0.0], [0.0]]])
    terminal = np.array([[[True], [False]], [[True], [True]]])
    return FiniteMDP(next_state, np.ones((2, 2, 1)), reward, terminal, np.array([1.0, 0.0]),
                     horizon=horizon)


def test_a_limit_bounds_what_a_loop_can_gather() -> None:
    assert return_range(chain(-1.0, horizon=5)) == (-5.0, 1.0)  # 5 costly steps; 1 at once
    assert return_range(chain(2.0, horizon=5)) == (1.0, 10.0)  # 5 paying steps, cut off


def test_with_no_limit_a_paying_or_costly_loop_leaves_that_side_unbounded() -> None:
    assert return_range(chain(-1.0, horizon=None)) == (-math.inf, 1.0)
    assert return_range(chain(2.0, horizon=None)) == (1.0, math.inf)
    assert return_range(chain(0.0, horizon=None)) == (0.0, 1.0)


@pytest.mark.parametrize(("game", "kwargs", "wrappers", "expected"), [
    ("cliffwalking", {}, [], (-20_000.0, -13.0)),  # 200 steps into the cliff; the shortest path
    ("cliffwalking", {}, [("TimeLimit", {"max_episode_steps": 50})], (-5_000.0, -13.0)),
    ("frozenlake", {}, [], (0.0, 1.0)),
    ("blackjack", {}, [], (-1.0, 1.0)),
    ("blackjack", {"natural": True}, [], (-1.0, 1.5)),
    ("blackjack", {}, [("ScaleReward", {"factor": 2.0})], (-2.0, 2.0)),
    ("gridworld", {}, [], (0.0, 1.0)),
])
def test_each_game_gives_the_returns_its_episodes_can_have(
    game: str, kwargs: dict, wrappers: list, expected: tuple[float, float]
) -> None:
    played = game_named(game)
    assert return_range_of(played, played.env_id, kwargs, wrappers) == expected


def test_wrappers_a_model_does_not_follow_leave_the_range_unknown() -> None:
    taxi = game_named("taxi")
    assert return_range_of(taxi, taxi.env_id, {}, [("StickyAction", {})]) is None
    assert return_range_of(taxi, taxi.env_id, {"no such": 1}, []) is None
