"""Tests for `tui_gym.envs.gridworld.GridWorldEnv`: API conformance, dynamics, rendering."""

from __future__ import annotations

import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.utils.passive_env_checker import env_render_passive_checker

import tui_gym  # noqa: F401  (registers the GridWorld ids)
from tui_gym.envs.gridworld import (
    ACTION_DELTAS,
    ACTION_NAMES,
    AGENT_COLOR,
    CELL_PIXELS,
    TARGET_COLOR,
    GridWorldEnv,
)

GRIDWORLD_IDS = ("tui_gym/GridWorld-v0", "gymnasium_env/GridWorld-v0")
RIGHT, UP, LEFT, DOWN = 0, 1, 2, 3
# The tutorial's mapping, written out independently of the module under test.
EXPECTED_DELTAS = {RIGHT: (1, 0), UP: (0, 1), LEFT: (-1, 0), DOWN: (0, -1)}


def manhattan(a: object, b: object) -> int:
    """The L1 distance between two grid positions, as a Python int."""
    return int(np.abs(np.asarray(a) - np.asarray(b)).sum())


def _positions(obs: dict[str, np.ndarray]) -> tuple[tuple[int, int], tuple[int, int]]:
    return tuple(int(v) for v in obs["agent"]), tuple(int(v) for v in obs["target"])


# -- Gymnasium conformance -------------------------------------------------


@pytest.mark.parametrize("render_mode", [None, "ansi", "human", "rgb_array"])
def test_check_env_passes_without_warnings_on_a_raw_env(render_mode: str | None) -> None:
    env = GridWorldEnv(render_mode=render_mode)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # A bare instance has no spec, so check_env cannot re-make it in every render
        # mode (it warns about that); the render check is done directly below instead.
        check_env(env.unwrapped, skip_render_check=True)
        if render_mode is not None:
            env.reset(seed=0)
            env_render_passive_checker(env)
    env.close()


@pytest.mark.parametrize("env_id", GRIDWORLD_IDS)
def test_check_env_passes_without_warnings_on_the_registered_env(env_id: str) -> None:
    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)  # includes every declared render mode, via the spec
    env.close()


def test_metadata_and_spaces() -> None:
    env = GridWorldEnv(size=7)
    assert env.metadata == {"render_modes": ["ansi", "human", "rgb_array"], "render_fps": 4}
    assert env.action_space == gym.spaces.Discrete(4)
    assert env.observation_space == gym.spaces.Dict(
        {
            "agent": gym.spaces.Box(0, 6, shape=(2,), dtype=np.int64),
            "target": gym.spaces.Box(0, 6, shape=(2,), dtype=np.int64),
        }
    )
    obs, _ = env.reset(seed=0)
    assert obs["agent"].dtype == np.int64 and obs["target"].dtype == np.int64
    assert env.observation_space.contains(obs)


@pytest.mark.parametrize("env_id", GRIDWORLD_IDS)
def test_registered_ids_truncate_after_300_steps(env_id: str) -> None:
    env = gym.make(env_id)
    assert env.spec is not None and env.spec.max_episode_steps == 300
    assert isinstance(env.unwrapped, GridWorldEnv)
    env.reset(seed=0, options={"agent": (0, 0), "target": (4, 4)})
    for step in range(1, 301):
        obs, reward, terminated, truncated, info = env.step(LEFT)  # into the wall
        assert not terminated
        assert truncated == (step == 300)
        assert _positions(obs)[0] == (0, 0)
        assert info == {"distance": 8}
    env.close()


def test_make_passes_keyword_arguments() -> None:
    env = gym.make("tui_gym/GridWorld-v0", size=3, reward_scale=2.0, step_penalty=0.5)
    assert env.unwrapped.size == 3
    env.reset(seed=0, options={"agent": (0, 0), "target": (1, 0)})
    assert env.step(UP)[1] == -0.5
    assert env.step(DOWN)[1] == -0.5
    assert env.step(RIGHT)[1:3] == (2.0, True)


def test_vector_env_steps_and_resets() -> None:
    envs = gym.make_vec("tui_gym/GridWorld-v0", num_envs=3)
    obs, info = envs.reset(seed=42)
    assert obs["agent"].shape == (3, 2) and obs["target"].shape == (3, 2)
    assert np.all(np.any(obs["agent"] != obs["target"], axis=1))
    np.testing.assert_array_equal(
        info["distance"], np.abs(obs["agent"] - obs["target"]).sum(axis=1)
    )
    envs.action_space.seed(42)
    for _ in range(50):
        obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())
        assert rewards.shape == terminated.shape == truncated.shape == (3,)
        assert envs.observation_space.contains(obs)
    obs, _ = envs.reset(seed=7)
    assert envs.observation_space.contains(obs)
    envs.close()


# -- dynamics --------------------------------------------------------------


def test_action_tables_match_the_tutorial() -> None:
    assert ACTION_NAMES == ("right", "up", "left", "down")
    assert tuple(tuple(d) for d in ACTION_DELTAS) == tuple(EXPECTED_DELTAS[a] for a in range(4))


@pytest.mark.parametrize("size", [2, 4])
def test_every_transition_follows_the_mapping_and_clips_at_walls(size: int) -> None:
    env = GridWorldEnv(size=size)
    walls_hit = set()
    for x in range(size):
        for y in range(size):
            # Any cell other than the agent's will do for the target.
            target = (x, (y + 1) % size)
            for action, (dx, dy) in EXPECTED_DELTAS.items():
                env.reset(seed=0, options={"agent": (x, y), "target": target})
                obs, reward, terminated, truncated, info = env.step(action)
                expected = (min(max(x + dx, 0), size - 1), min(max(y + dy, 0), size - 1))
                if expected == (x, y):
                    walls_hit.add(action)
                assert _positions(obs) == (expected, target)
                assert env.agent_position == expected
                assert terminated == (expected == target)
                assert truncated is False
                assert reward == (1.0 if terminated else 0.0)
                assert info == {"distance": manhattan(expected, target)}
    assert walls_hit == {RIGHT, UP, LEFT, DOWN}


def test_resets_never_overlap_and_are_roughly_uniform() -> None:
    size, n = 4, 8000
    cells = size * size
    env = GridWorldEnv(size=size)
    agent_counts = np.zeros((size, size), dtype=np.int64)
    target_counts = np.zeros((size, size), dtype=np.int64)
    env.reset(seed=2024)
    for _ in range(n):
        obs, info = env.reset()
        agent, target = _positions(obs)
        assert agent != target
        assert info["distance"] == manhattan(agent, target) >= 1
        agent_counts[agent] += 1
        target_counts[target] += 1
    # Agent uniform over all cells; target uniform over the other cells, hence
    # uniform marginally too. Each count is Binomial(n, 1/cells).
    p = 1 / cells
    mean, sd = n * p, math.sqrt(n * p * (1 - p))
    for counts in (agent_counts, target_counts):
        assert counts.sum() == n
        assert np.all(np.abs(counts - mean) <= 5 * sd), counts


def test_target_is_never_on_the_agent_even_on_the_smallest_grid() -> None:
    env = GridWorldEnv(size=2)
    env.reset(seed=5)
    for _ in range(500):
        agent, target = _positions(env.reset()[0])
        assert agent != target


def test_same_seed_gives_the_same_episode() -> None:
    def episode(seed: int) -> list[tuple]:
        env = GridWorldEnv(size=6, step_penalty=0.1)
        obs, info = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        trace: list[tuple] = [(_positions(obs), info["distance"])]
        for _ in range(40):
            obs, reward, terminated, truncated, info = env.step(int(rng.integers(4)))
            trace.append((_positions(obs), reward, terminated, truncated, info["distance"]))
            if terminated:
                obs, info = env.reset()
                trace.append((_positions(obs), info["distance"]))
        return trace

    assert episode(11) == episode(11)
    assert episode(11) != episode(12)


def test_reset_options_place_agent_and_target() -> None:
    env = GridWorldEnv(size=5)
    obs, info = env.reset(seed=0, options={"agent": (0, 4), "target": np.array([4, 0])})
    assert _positions(obs) == ((0, 4), (4, 0))
    assert info == {"distance": 8}
    # Only one of them given: the other is random but never on the same cell.
    for seed in range(50):
        agent, target = _positions(env.reset(seed=seed, options={"agent": (2, 2)})[0])
        assert agent == (2, 2) and target != agent
        agent, target = _positions(env.reset(seed=seed, options={"target": (1, 3)})[0])
        assert target == (1, 3) and agent != target


@pytest.mark.parametrize(
    "options",
    [
        {"agent": (5, 0), "target": (0, 0)},
        {"agent": (0, -1), "target": (0, 0)},
        {"agent": (0, 0, 0), "target": (1, 1)},
        {"agent": (0.5, 0), "target": (1, 1)},
        {"agent": (1, 1), "target": (1, 1)},
        {"agnet": (1, 1)},
    ],
)
def test_bad_reset_options_raise(options: dict) -> None:
    env = GridWorldEnv(size=5)
    with pytest.raises(ValueError, match="GridWorld reset option"):
        env.reset(seed=0, options=options)


def test_invalid_action_raises() -> None:
    env = GridWorldEnv()
    env.reset(seed=0)
    for action in (4, -1, 1.5):
        with pytest.raises(ValueError, match="action"):
            env.step(action)


def test_step_before_reset_raises() -> None:
    env = GridWorldEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(0)


# -- fresh observations ----------------------------------------------------


def test_observations_are_fresh_and_do_not_alias_the_env() -> None:
    env = GridWorldEnv(size=5)
    obs0, info0 = env.reset(seed=0, options={"agent": (1, 1), "target": (3, 3)})
    obs0["agent"][:] = 4
    obs0["target"][0] = 0
    info0["distance"] = -1
    assert (env.agent_position, env.target_position) == ((1, 1), (3, 3))

    obs1, _, _, _, info1 = env.step(RIGHT)
    assert _positions(obs1) == ((2, 1), (3, 3))
    assert info1 == {"distance": 3}
    obs2, _, _, _, _ = env.step(LEFT)  # back where obs0 started: equal values, new objects
    assert _positions(obs2) == ((1, 1), (3, 3))
    for a, b in ((obs0, obs1), (obs1, obs2), (obs0, obs2)):
        assert a is not b
        for key in ("agent", "target"):
            assert a[key] is not b[key]
            assert not np.shares_memory(a[key], b[key])

    obs2["agent"][:] = 3  # would put the agent on the target, if it aliased
    _, reward, terminated, _, _ = env.step(UP)
    assert env.agent_position == (1, 2)
    assert (reward, terminated) == (0.0, False)


def test_reset_option_arrays_are_copied() -> None:
    env = GridWorldEnv(size=5)
    agent = np.array([0, 0])
    env.reset(seed=0, options={"agent": agent, "target": (4, 4)})
    agent[:] = 4
    assert env.agent_position == (0, 0)


# -- rewards and arguments ---------------------------------------------------


def test_reward_scale_and_step_penalty() -> None:
    env = GridWorldEnv(size=3, reward_scale=2.5, step_penalty=0.25)
    env.reset(seed=0, options={"agent": (0, 0), "target": (2, 0)})
    rewards = []
    for action in (LEFT, RIGHT, RIGHT):
        _, reward, terminated, truncated, _ = env.step(action)
        rewards.append((reward, terminated, truncated))
    assert rewards == [(-0.25, False, False), (-0.25, False, False), (2.5, True, False)]


def test_default_rewards_are_plus_one_and_plain_zero() -> None:
    env = GridWorldEnv(size=3)
    env.reset(seed=0, options={"agent": (0, 0), "target": (1, 0)})
    _, reward, _, _, _ = env.step(UP)
    assert reward == 0.0 and math.copysign(1.0, reward) == 1.0  # not -0.0
    env.step(DOWN)
    assert env.step(RIGHT)[1:3] == (1.0, True)


@pytest.mark.parametrize("size", [1, 0, -3, 2.0, 3.5, "5", None, True])
def test_bad_size_raises(size: object) -> None:
    with pytest.raises(ValueError, match="size must be an integer >= 2") as excinfo:
        GridWorldEnv(size=size)  # type: ignore[arg-type]
    assert f"got {size!r}" in str(excinfo.value)


def test_bad_size_message_is_exact() -> None:
    with pytest.raises(ValueError) as excinfo:
        GridWorldEnv(size=1)
    assert str(excinfo.value) == "GridWorld size must be an integer >= 2, got 1"


def test_numpy_integer_size_is_accepted() -> None:
    env = GridWorldEnv(size=np.int64(3))
    assert env.size == 3 and type(env.size) is int


@pytest.mark.parametrize("reward_scale", [math.inf, -math.inf, math.nan, "1"])
def test_bad_reward_scale_raises(reward_scale: object) -> None:
    with pytest.raises(ValueError, match="reward_scale"):
        GridWorldEnv(reward_scale=reward_scale)  # type: ignore[arg-type]


@pytest.mark.parametrize("step_penalty", [-0.1, math.inf, math.nan, "0"])
def test_bad_step_penalty_raises(step_penalty: object) -> None:
    with pytest.raises(ValueError, match="step_penalty"):
        GridWorldEnv(step_penalty=step_penalty)  # type: ignore[arg-type]


def test_bad_render_mode_raises_listing_the_modes() -> None:
    with pytest.raises(ValueError, match="render_mode") as excinfo:
        GridWorldEnv(render_mode="rgb")
    message = str(excinfo.value)
    for mode in ("None", "'ansi'", "'human'", "'rgb_array'", "'rgb'"):
        assert mode in message


# -- rendering -------------------------------------------------------------


def _grid_rows(text: str) -> list[str]:
    """The grid's rows, top first, as strings of cell symbols (border stripped)."""
    lines = text.splitlines()
    assert lines[0] == lines[-1] and set(lines[0]) <= {"+", "-"}
    return ["".join(line.strip("|").split()) for line in lines[1:-1]]


def test_ansi_render_puts_high_y_on_top_so_up_moves_up() -> None:
    env = GridWorldEnv(render_mode="ansi", size=5)
    env.reset(seed=0, options={"agent": (1, 3), "target": (3, 0)})
    rows = _grid_rows(env.render())
    assert rows == [".....", ".A...", ".....", ".....", "...T."]

    env.step(UP)
    rows = _grid_rows(env.render())
    assert rows[0] == ".A..." and rows[1] == "....."
    env.step(RIGHT)
    assert _grid_rows(env.render())[0] == "..A.."


def test_ansi_render_marks_the_agent_on_the_target() -> None:
    env = GridWorldEnv(render_mode="ansi", size=3)
    env.reset(seed=0, options={"agent": (0, 0), "target": (0, 1)})
    env.step(UP)
    assert _grid_rows(env.render()) == ["...", "*..", "..."]


def _cell_centre(env: GridWorldEnv, x: int, y: int) -> tuple[int, int]:
    row = (env.size - 1 - y) * CELL_PIXELS + CELL_PIXELS // 2
    col = x * CELL_PIXELS + CELL_PIXELS // 2
    return row, col


def test_rgb_array_render_shape_colours_and_orientation() -> None:
    env = GridWorldEnv(render_mode="rgb_array", size=5)
    env.reset(seed=0, options={"agent": (1, 3), "target": (3, 0)})
    image = env.render()
    assert isinstance(image, np.ndarray)
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
    assert image.shape[0] == image.shape[1] >= 5 * CELL_PIXELS

    assert tuple(image[_cell_centre(env, 1, 3)]) == AGENT_COLOR
    assert tuple(image[_cell_centre(env, 3, 0)]) == TARGET_COLOR
    for x in range(5):
        for y in range(5):
            if (x, y) not in {(1, 3), (3, 0)}:
                colour = tuple(image[_cell_centre(env, x, y)])
                assert colour not in {AGENT_COLOR, TARGET_COLOR}, (x, y)
    # The target sits on the bottom row of the picture, as in the text render.
    target_rows = np.nonzero(np.all(image == TARGET_COLOR, axis=2))[0]
    assert target_rows.min() > 4 * CELL_PIXELS

    env.step(UP)
    moved = env.render()
    assert tuple(moved[_cell_centre(env, 1, 4)]) == AGENT_COLOR
    assert tuple(moved[_cell_centre(env, 1, 3)]) != AGENT_COLOR
    assert moved is not image


def test_rgb_array_render_does_not_alias_between_calls() -> None:
    env = GridWorldEnv(render_mode="rgb_array", size=3)
    env.reset(seed=0, options={"agent": (0, 0), "target": (2, 2)})
    first = env.render()
    first[:] = 0
    second = env.render()
    assert tuple(second[_cell_centre(env, 0, 0)]) == AGENT_COLOR
    assert second.max() == 255


def test_human_render_prints_on_reset_and_step(capsys: pytest.CaptureFixture[str]) -> None:
    env = GridWorldEnv(render_mode="human", size=3)
    env.reset(seed=0, options={"agent": (0, 0), "target": (2, 2)})
    printed = capsys.readouterr().out
    assert _grid_rows(printed.strip()) == ["..T", "...", "A.."]

    env.step(UP)
    printed = capsys.readouterr().out
    assert _grid_rows(printed.strip()) == ["..T", "A..", "..."]
    assert env.render() is None
    assert capsys.readouterr().out.strip() == printed.strip()


def test_render_without_mode_warns_and_returns_none() -> None:
    env = GridWorldEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None
