"""Sutton & Barto's chapter 6-8 worlds: the random walk's true values, Windy GridWorld's
optimum and wind, the mazes' walls and the world that changes, the maximization-bias MDP's
noisy rewards; and what a model with reward noise and a world in phases hand out."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from tui_gym.bench.defaults import one_run
from tui_gym.core.mdp import FiniteMDP, ModelError, NotAvailable, Phases, evaluate
from tui_gym.core.wrappers import parse_wrapper_spec
from tui_gym.envs.dyna_maze import BlockingMazeEnv, ShortcutMazeEnv
from tui_gym.envs.max_bias import A, B, MaxBiasEnv
from tui_gym.games import game_named
from tui_gym.games.model import PHASE, ModelGame
from tui_gym.session.session import Session

Z = 4.0  # standard errors a sampled figure may stray from the exact one


def _game(name: str) -> ModelGame:
    game = game_named(name)
    assert isinstance(game, ModelGame)
    return game


def _uniform(model: FiniteMDP) -> np.ndarray:
    return np.full((model.n_states, model.n_actions), 1.0 / model.n_actions)


# --- the random walk -------------------------------------------------------------------


@pytest.mark.parametrize(("states", "values"), [
    (5, [1 / 6, 2 / 6, 3 / 6, 4 / 6, 5 / 6]),  # Example 6.2: A to E
    (19, [i / 10 for i in range(-9, 10)]),  # Figure 7.2: -0.9 to 0.9
])
def test_the_random_policy_has_the_books_values_on_the_walk(states: int, values: list) -> None:
    game = _game("random-walk")
    model = game.base_model(game.normalize_kwargs({"states": states}))
    v = evaluate(model, _uniform(model)).v
    assert np.allclose(v[1:-1], values, atol=1e-9)
    assert v[0] == v[-1] == 0.0  # the ends
    names = [game.states.describe(s, {"states": states}) for s in range(1, states + 1)]
    assert names[0] == ("state A" if states == 5 else "state 1")


def test_the_walk_takes_5_or_19_states_only() -> None:
    game = game_named("random-walk")
    with pytest.raises(ValueError, match="5 .*or 19"):
        game.normalize_kwargs({"states": 7})


# --- Windy GridWorld -------------------------------------------------------------------


@pytest.mark.parametrize(("name", "steps"), [("windy", 15), ("windy-king", 7)])
def test_the_optimum_crosses_the_wind_in_15_steps_or_7_with_kings_moves(
    name: str, steps: int
) -> None:
    game = _game(name)
    kwargs = game.normalize_kwargs({})
    optimum = game.oracle.optimum(kwargs)
    assert not isinstance(optimum, NotAvailable) and optimum.value == -steps
    # The optimum's moves, played on the env: the goal in that many steps.
    env = gym.make(game.env_id)
    obs, _ = env.reset(seed=0)
    assert optimum.q is not None
    taken = 0
    while taken < 100:
        taken += 1
        obs, reward, terminated, truncated, _ = env.step(int(np.argmax(optimum.q[obs])))
        assert reward == -1.0 and not truncated
        if terminated:
            break
    assert taken == steps and obs == 3 * 10 + 7


def test_the_wind_pushes_a_move_up_by_its_starting_column() -> None:
    env = gym.make("tui_gym/WindyGridWorld-v0").unwrapped
    env.reset(seed=0)
    for col, wind in enumerate((0, 0, 0, 1, 1, 1, 2, 2, 1, 0)):
        env.s = 5 * 10 + col  # row 5
        obs, *_ = env.step(1)  # down: one row down, then the wind
        assert obs == (6 - wind) * 10 + col
    env.s = 0 * 10 + 6  # the top row: the wind cannot push further
    obs, *_ = env.step(3)
    assert obs == 0 * 10 + 7


def test_a_gusty_wind_blows_one_stronger_or_weaker_a_third_of_the_time_each() -> None:
    game = _game("windy")
    model = game.base_model(game.normalize_kwargs({"stochastic_wind": True}))
    right = 3
    outcomes = model.outcomes(4 * 10 + 6, right)  # row 4, column 6: wind 2
    assert sorted(s for _, s, _, _ in outcomes) == [1 * 10 + 7, 2 * 10 + 7, 3 * 10 + 7]
    assert [p for p, _, _, _ in outcomes] == pytest.approx([1 / 3] * 3)
    assert [s for _, s, _, _ in model.outcomes(4 * 10 + 1, right)] == [4 * 10 + 2]  # no wind
    solved = game.oracle.optimum(game.normalize_kwargs({"stochastic_wind": True}))
    assert not isinstance(solved, NotAvailable) and -30 < solved.value < -7


# --- the mazes -------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "fewest"), [
    ("dyna-maze", (14,)), ("blocking-maze", (10, 16)), ("shortcut-maze", (16, 10))])
def test_each_phase_of_a_maze_has_its_own_shortest_way(name: str, fewest: tuple) -> None:
    game = _game(name)
    kwargs = game.normalize_kwargs({})
    assert len(game.phase_starts(kwargs)) == len(fewest)
    for phase, steps in enumerate(fewest):
        exact = game.in_phase(kwargs, phase)
        optimum = game.oracle.optimum(exact)
        assert not isinstance(optimum, NotAvailable) and optimum.marks is not None
        # Every way to the goal is worth +1: the marks are the quickest of them.
        reference = game.oracle.reference(optimum.marks.astype(float), exact)
        assert not isinstance(reference, NotAvailable)
        assert reference.figures["optimal_steps"] == reference.figures["mean_steps"] == steps
        assert reference.figures["extra_steps"] == 0.0


def test_the_maze_changes_at_the_given_step_over_episodes_and_a_seed_starts_it_over() -> None:
    env = BlockingMazeEnv(change_at=5)
    _, info = env.reset(seed=1)
    assert (info["phase"], info["changes_in"]) == (0, 5)
    before = env.grid.cells()
    env.step(2)  # left, left: the start is in the bottom row
    env.step(2)
    _, info = env.reset()  # a new episode: the world's count carries on
    assert (info["world_steps"], info["changes_in"]) == (2, 3)
    for _ in range(3):
        _, _, _, _, info = env.step(0)
    assert info["phase"] == 1 and "changes_in" not in info and env.grid.cells() != before
    assert env.grid.cells()[3] == "FWWWWWWWW"  # the way round the left end is open
    _, info = env.reset(seed=1)
    assert info["phase"] == 0 and env.grid.cells() == before
    _, info = env.reset(options={"world_steps": 4})  # a clock set from elsewhere
    assert (info["world_steps"], info["phase"], info["changes_in"]) == (4, 0, 1)
    _, info = env.reset(options={"world_steps": 7})
    assert info["phase"] == 1 and env.grid.cells()[3] == "FWWWWWWWW"
    with pytest.raises(ValueError, match="world_steps must be an integer >= 0"):
        env.reset(options={"world_steps": -1})


@pytest.mark.parametrize("env_class", [BlockingMazeEnv, ShortcutMazeEnv])
def test_the_model_of_each_phase_agrees_with_every_move_of_the_env(env_class) -> None:
    game = _game("blocking-maze" if env_class is BlockingMazeEnv else "shortcut-maze")
    kwargs = game.normalize_kwargs({"change_at": 1})
    for phase, env in enumerate((env_class(change_at=10**9), env_class(change_at=1))):
        env.reset(seed=0)
        env.step(0)  # the second env is in its second phase from here on
        assert env.phase == phase
        model = game.base_model(game.in_phase(kwargs, phase))
        for s in range(model.n_states):
            for a in range(model.n_actions):
                env.s = s
                nxt, reward, terminated, _, _ = env.step(a)
                assert [(nxt, reward, terminated)] == [o[1:] for o in model.outcomes(s, a)]


# Seeds whose defaults ended short on the mazes: prioritized sweeping walking into
# the new wall, a detour kept or the goal lost by the learners that look ahead on-policy,
# Double Q and Q(lambda) not settled, Monte Carlo's averages holding its first, nearly random
# episodes on the Dyna maze (`tui-gym bench` counts every seed).
@pytest.mark.parametrize(("name", "algorithm", "seed"), [
    ("blocking-maze", "prioritized-sweeping", 1), ("blocking-maze", "sarsa-lambda", 3),
    ("blocking-maze", "n-step-sarsa", 13), ("blocking-maze", "monte-carlo", 8),
    ("shortcut-maze", "sarsa-lambda", 1), ("shortcut-maze", "monte-carlo", 2),
    ("shortcut-maze", "double-q", 6), ("shortcut-maze", "q-lambda", 9),
    ("dyna-maze", "monte-carlo", 1), ("dyna-maze", "monte-carlo", 213)])
def test_a_mazes_defaults_reach_its_bound(name: str, algorithm: str, seed: int) -> None:
    met, value, text, _, _ = one_run(name, algorithm, seed)
    assert met, (text, value)


def test_dyna_q_plus_defaults_find_the_shortcut_and_dyna_qs_keep_the_long_way() -> None:
    # Figure 8.5 with each learner's defaults: the bonus, not exploration, finds the shortcut,
    # and the greedy policy of the bonus-laden Q takes it without a detour or a loop.
    for algorithm, extra_steps in (("dyna-q-plus", 0.0), ("dyna-q", 6.0)):
        _, value, _, _, _ = one_run("shortcut-maze", algorithm, 0)
        assert value == extra_steps, algorithm


def test_a_session_measures_against_the_phase_in_force_after_its_steps() -> None:
    session = Session("blocking-maze", {"change_at": 50}, seed=0)
    assert session.exact_kwargs() == {"change_at": 50, PHASE: 0}
    session.trainer.run(episodes=30)
    assert session.trainer.steps > 50 and session.exact_kwargs()[PHASE] == 1
    reference = session.reference()
    assert reference is not None and reference.figures["optimal_steps"] == 16
    panels = session.heatmaps()
    assert panels  # the wall as it is now: open at its left end, closed at its right
    assert panels[0].labels[3][0] != "█" and panels[0].labels[3][1:] == ("█",) * 8


@pytest.mark.parametrize(("name", "algorithm"), [("blocking-maze", "dyna-q"),
                                               ("shortcut-maze", "sarsa")])
def test_the_compiled_loop_plays_the_world_that_changes_as_the_env_does(name: str,
                                                                       algorithm: str) -> None:
    tables = {}
    for engine in ("model", "env"):
        session = Session(name, {"change_at": 300}, seed=2, algorithm=algorithm, engine=engine,
                          hp={"episodes": 60})
        assert session.trainer.engine == engine
        session.trainer.run(episodes=60)
        assert session.trainer.steps > 300 and session.exact_kwargs()[PHASE] == 1
        tables[engine] = (session.trainer.steps, session.agent.table()[0])
    assert tables["model"][0] == tables["env"][0]
    assert np.array_equal(tables["model"][1], tables["env"][1])


def test_the_env_goes_on_at_the_step_the_compiled_loop_reached() -> None:
    session = Session("blocking-maze", {"change_at": 40}, seed=0, hp={"episodes": 50})
    trainer = session.trainer
    assert session.engine_reason.startswith("model:") and len(trainer.phases) == 2
    trainer.run(episodes=1)
    while trainer.steps < 40:  # past the change, on the compiled loop
        trainer.run(episodes=1)
    trainer.step()  # the animated board's next move, on the env
    maze = session.env.unwrapped
    assert (maze.world_steps, maze.phase) == (trainer.steps, 1)
    assert maze.grid.cells()[3] == "FWWWWWWWW"


def test_the_world_hands_out_each_phase_as_the_wrappers_make_it() -> None:
    limit = parse_wrapper_spec("TimeLimit:max_episode_steps=30")
    session = Session("shortcut-maze", {"change_at": 40}, (limit,), seed=0)
    game = _game("shortcut-maze")
    world = game.world(session.env_kwargs, session.changes)
    assert isinstance(world, Phases) and world.starts == (0, 40)
    assert [m.horizon for m in world.models] == [30, 30]
    assert not np.array_equal(world.models[0].next_state, world.models[1].next_state)
    one = _game("dyna-maze").world({})
    assert isinstance(one, Phases) and len(one.models) == 1 and one.starts == (0,)
    assert game.make_kwargs(game.at_step(session.env_kwargs, 99)) == {"change_at": 40}


# --- the maximization-bias MDP --------------------------------------------------------


def test_the_model_keeps_the_mean_of_bs_rewards_and_the_env_draws_around_it() -> None:
    game = _game("max-bias")
    kwargs = game.normalize_kwargs({})
    model = game.base_model(kwargs)
    assert model.reward_std is not None
    assert np.all(model.reward[B] == -0.1) and np.all(model.reward_std[B] == 1.0)
    assert not model.reward_std[A].any()
    env = MaxBiasEnv()
    draws = []
    env.reset(seed=7)
    for _ in range(2000):
        env.reset()
        env.step(0)  # left, to B
        draws.append(env.step(5)[1])
    sample = np.asarray(draws)
    assert abs(sample.mean() + 0.1) <= Z / math.sqrt(len(sample))
    assert abs(sample.std() - 1.0) <= 0.1
    again = MaxBiasEnv()
    again.reset(seed=7)
    again.reset()
    again.step(0)
    assert again.step(5)[1] == draws[0]  # the env's own seeded generator


def test_the_optimum_goes_right_among_the_actions_a_offers() -> None:
    game = _game("max-bias")
    kwargs = game.normalize_kwargs({"actions": 4})
    optimum = game.oracle.optimum(kwargs)
    assert not isinstance(optimum, NotAvailable) and optimum.value == 0.0
    assert optimum.q is not None and optimum.q[A, 0] == pytest.approx(-0.1)
    env = gym.make(game.env_id, **game.make_kwargs(kwargs))
    _, info = env.reset(seed=0)
    assert list(info["action_mask"]) == [1, 1] + [0] * 10
    advice = game.oracle.advice(env, kwargs)
    assert advice.optimal == (1,) and set(advice.values or {}) == {0, 1}
    _, _, _, _, info = env.step(0)
    assert list(info["action_mask"]) == [0, 0, 1, 1, 1, 1] + [0] * 6
    advice = game.oracle.advice(env, kwargs)
    assert advice.optimal == (2, 3, 4, 5)  # B's four: each as good as the others
    offered = game.offered_actions(kwargs)
    assert offered.shape == (4, 12) and offered[B].sum() == 4
    marks = game.oracle.optimal_marks(kwargs)
    assert isinstance(marks, np.ndarray) and not (marks & ~offered).any()


def test_noise_scales_with_a_scaled_reward_and_a_clipped_one_is_not_followed() -> None:
    model = _game("max-bias").base_model({})
    assert model.reward_std is not None and model.reward_std[B, 0, 0] == 1.0
    scaled = Session("max-bias", {}, (parse_wrapper_spec("ScaleReward:factor=-2"),), seed=0)
    exact = scaled.game.oracle.exact(scaled.env_kwargs, scaled.changes)
    assert not isinstance(exact, NotAvailable) and exact.scope.exact
    assert exact.model.reward_std is not None and exact.model.reward_std[B, 0, 0] == 2.0
    assert exact.model.reward[B, 0, 0] == pytest.approx(0.2)
    clipped = Session("max-bias", {}, (parse_wrapper_spec("ClipReward:min_reward=-1,"
                                                          "max_reward=1"),), seed=0)
    scope = clipped.game.oracle.scope(clipped.env_kwargs, clipped.changes)
    assert not scope.exact and "noise" in scope.note


# --- reward noise and phases in the model ---------------------------------------------


def _tiny(**extra) -> FiniteMDP:
    shape = (1, 1, 1)
    return FiniteMDP(np.zeros(shape, dtype=np.int64), np.ones(shape), np.zeros(shape),
                     np.ones(shape, dtype=bool), np.ones(1), **extra)


def test_a_reward_deviation_is_checked_like_the_other_arrays() -> None:
    assert _tiny().reward_std is None
    model = _tiny(reward_std=np.full((1, 1, 1), 0.5))
    assert model.reward_std is not None and not model.reward_std.flags.writeable
    assert model.replace(reward=np.ones((1, 1, 1))).reward_std[0, 0, 0] == 0.5
    with pytest.raises(ModelError, match="reward_std has shape"):
        _tiny(reward_std=np.ones((1, 1, 2)))
    with pytest.raises(ModelError, match="deviation"):
        _tiny(reward_std=np.full((1, 1, 1), -1.0))
    with pytest.raises(ModelError, match="deviation"):
        _tiny(reward_std=np.full((1, 1, 1), np.nan))


def test_phases_start_at_step_0_and_follow_one_another() -> None:
    model = _tiny()
    phases = Phases((model,) * 3, (0, 10, 25))
    assert phases.starts == (0, 10, 25) and phases.models == (model,) * 3
    for starts in ((1, 10), (0, 0), (0, 20, 10)):
        with pytest.raises(ModelError, match="start"):
            Phases((model,) * len(starts), starts)
    with pytest.raises(ModelError, match="differ in size"):
        Phases((model, _game("max-bias").base_model({})), (0, 5))


def test_the_coach_advises_for_the_phase_of_the_env_being_played() -> None:
    game = _game("blocking-maze")
    kwargs = game.normalize_kwargs({"change_at": 1})
    env = gym.make(game.env_id, **game.make_kwargs(kwargs))
    env.reset(seed=0)
    start = 5 * 9 + 3
    # Up or right, round the wall's right end (left is not on a shortest way).
    assert game.oracle.advice(env, kwargs).optimal == (0, 3)
    env.step(1)  # down, into the bottom edge: still at the start, and the wall has moved
    assert env.unwrapped.s == start and env.unwrapped.phase == 1
    assert game.oracle.advice(env, kwargs).optimal == (0, 2)  # up or left: round its left
