"""The wrapper catalog: params, parsing, fitting, building, and each wrapper's visible effect."""

from __future__ import annotations

import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.core.wrappers import (
    CATALOG,
    Param,
    UnknownEnvError,
    UnknownWrapperError,
    WrapperChoice,
    WrapperMismatchError,
    build_env,
    build_env_lenient,
    check_choices,
    format_wrapper_spec,
    get_spec,
    parse_wrapper_spec,
)

GRID = "tui_gym/GridWorld-v0"
RIGHT, UP, LEFT, DOWN = 0, 1, 2, 3
W = WrapperChoice.make

ALL_PARAMS = [(spec.name, param) for spec in CATALOG.values() for param in spec.params]
NUMERIC_PARAMS = [(name, p) for name, p in ALL_PARAMS if p.kind is not bool]


def place(env: gym.Env, agent: tuple[int, int], target: tuple[int, int], seed: int = 0) -> Any:
    obs, _ = env.reset(seed=seed, options={"agent": agent, "target": target})
    return obs


# -- the catalog ----------------------------------------------------------------


def test_catalog_lists_the_wrappers_in_teaching_order() -> None:
    assert list(CATALOG) == [
        "TimeLimit",
        "FlattenObservation",
        "TimeAwareObservation",
        "StickyAction",
        "DelayObservation",
        "ClipReward",
        "ScaleReward",
        "StepPenalty",
        "DistanceShaping",
    ]
    for spec in CATALOG.values():
        assert spec.summary and "\n" not in spec.summary
        assert all(param.owner == spec.name and param.help for param in spec.params)


def test_only_observation_wrappers_invalidate_a_q_table() -> None:
    changing = {name for name, spec in CATALOG.items() if spec.changes_observation}
    assert changing == {"FlattenObservation", "TimeAwareObservation", "DelayObservation"}


def test_get_spec_ignores_case_and_names_the_known_wrappers() -> None:
    assert get_spec("timelimit") is CATALOG["TimeLimit"]
    assert get_spec(" STEPPENALTY ") is CATALOG["StepPenalty"]
    with pytest.raises(UnknownWrapperError) as caught:
        get_spec("FrameSkip")
    message = str(caught.value)
    assert "'FrameSkip'" in message
    assert all(name in message for name in CATALOG)
    assert isinstance(caught.value, ValueError)


# -- params ---------------------------------------------------------------------


def test_param_error_names_field_and_range() -> None:
    with pytest.raises(ValueError) as caught:
        CATALOG["TimeLimit"].param("max_episode_steps").parse("abc")
    assert str(caught.value) == (
        "TimeLimit.max_episode_steps must be an integer in [1, 100000], got 'abc'"
    )


def test_describe_range() -> None:
    assert CATALOG["TimeLimit"].param("max_episode_steps").describe_range() == "[1, 100000]"
    sticky = CATALOG["StickyAction"].param("repeat_action_probability")
    assert sticky.describe_range() == "[0, 0.99]"
    assert CATALOG["TimeAwareObservation"].param("flatten").describe_range() == "true or false"
    assert Param("x", float, 0.0).describe_range() == "(-inf, inf)"


def test_param_reads_text_and_numbers() -> None:
    steps = CATALOG["TimeLimit"].param("max_episode_steps")
    assert steps.parse(" 50 ") == 50
    assert steps.parse(50.0) == 50
    assert steps.parse("1e2") == 100
    assert steps.parse(np.int64(7)) == 7
    factor = CATALOG["ScaleReward"].param("factor")
    assert factor.parse("-2.5") == -2.5
    assert isinstance(factor.parse(3), float)
    flatten = CATALOG["TimeAwareObservation"].param("flatten")
    assert [flatten.parse(v) for v in ("true", "No", " on ", "0", True, 1)] == [
        True,
        False,
        True,
        False,
        True,
        True,
    ]


@pytest.mark.parametrize(("wrapper", "param"), NUMERIC_PARAMS, ids=lambda x: getattr(x, "name", x))
def test_numeric_param_rejects_out_of_range_and_non_numbers(wrapper: str, param: Param) -> None:
    assert param.minimum is not None and param.maximum is not None
    step = 1 if param.kind is int else 0.5
    bad = [param.minimum - step, param.maximum + step, "abc", "", "nan", "inf", True]
    if param.kind is int:
        bad.append("2.5")
    for raw in bad:
        with pytest.raises(ValueError) as caught:
            param.parse(raw)
        message = str(caught.value)
        assert message.startswith(
            (f"{wrapper}.{param.name} must be ", f"{wrapper}.{param.name} is out of range: ")
        )
        assert param.describe_range() in message
        assert repr(raw) in message
    assert param.parse(str(param.default)) == param.default
    assert param.parse(param.minimum) == param.minimum
    assert param.parse(param.maximum) == param.maximum


@pytest.mark.parametrize(
    ("wrapper", "param"),
    [(name, p) for name, p in ALL_PARAMS if p.kind is bool],
    ids=lambda x: getattr(x, "name", x),
)
def test_bool_param_rejects_other_words(wrapper: str, param: Param) -> None:
    for raw in ("maybe", "2", 2, 0.5):
        with pytest.raises(ValueError, match=rf"^{wrapper}\.{param.name} must be true or false"):
            param.parse(raw)


def test_validate_fills_defaults_and_rejects_unknown_names() -> None:
    sticky = CATALOG["StickyAction"]
    assert sticky.validate({"repeat_action_probability": "0.5"}) == {
        "repeat_action_probability": 0.5,
        "repeat_action_duration": 1,
    }
    with pytest.raises(ValueError) as caught:
        sticky.validate({"probability": 0.5})
    assert str(caught.value) == (
        "StickyAction has no parameter 'probability'; "
        "valid: repeat_action_probability, repeat_action_duration"
    )
    with pytest.raises(ValueError, match="FlattenObservation has no parameter 'x'; it takes no"):
        CATALOG["FlattenObservation"].validate({"x": 1})


def test_clip_reward_rejects_min_above_max() -> None:
    with pytest.raises(ValueError) as caught:
        W("ClipReward", min_reward=2, max_reward=1)
    assert str(caught.value) == (
        "ClipReward.min_reward (2.0) must be <= ClipReward.max_reward (1.0)"
    )
    assert W("ClipReward", min_reward=1, max_reward=1).values() == {
        "max_reward": 1.0,
        "min_reward": 1.0,
    }


# -- choices and the CLI syntax ---------------------------------------------------


def test_choice_is_canonical_and_hashable() -> None:
    made = W("clipreward", max_reward="1", min_reward=-1)
    direct = WrapperChoice("ClipReward", (("min_reward", -1.0), ("max_reward", 1.0)))
    assert made == direct
    assert made.params == (("max_reward", 1.0), ("min_reward", -1.0))
    assert len({made, direct}) == 1
    assert WrapperChoice("cliprEWARD", direct.params) == direct  # names are canonical
    assert str(made) == "ClipReward:min_reward=-1.0,max_reward=1.0"


def _non_default(param: Param) -> bool | int | float:
    if param.kind is bool:
        return not param.default
    assert param.minimum is not None and param.maximum is not None
    if param.kind is int:
        return param.maximum if param.default != param.maximum else param.minimum
    return param.minimum + (param.maximum - param.minimum) / 3


@pytest.mark.parametrize("name", list(CATALOG))
def test_parse_and_format_round_trip(name: str) -> None:
    spec = CATALOG[name]
    defaults = W(name)
    assert parse_wrapper_spec(name) == defaults
    assert parse_wrapper_spec(format_wrapper_spec(defaults)) == defaults
    changed = W(name, **{p.name: _non_default(p) for p in spec.params})
    text = format_wrapper_spec(changed)
    assert parse_wrapper_spec(text) == changed
    assert format_wrapper_spec(parse_wrapper_spec(text)) == text
    assert parse_wrapper_spec(f"  {name.lower()} ") == defaults


def test_parse_reads_the_documented_examples() -> None:
    assert parse_wrapper_spec("TimeLimit:max_episode_steps=50") == W(
        "TimeLimit", max_episode_steps=50
    )
    assert parse_wrapper_spec("ClipReward: min_reward = -1 , max_reward=1").values() == {
        "min_reward": -1.0,
        "max_reward": 1.0,
    }
    assert format_wrapper_spec(W("FlattenObservation")) == "FlattenObservation"


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("", "has no wrapper name"),
        (":max_episode_steps=5", "has no wrapper name"),
        ("TimeLimit:max_episode_steps", "'max_episode_steps' is not key=value"),
        ("TimeLimit:=5", "'=5' is not key=value"),
        ("TimeLimit:max_episode_steps=", "is not key=value"),
        ("TimeLimit:max_episode_steps=5,,", "'' is not key=value"),
        ("TimeLimit:max_episode_steps=5,max_episode_steps=6", "sets 'max_episode_steps' twice"),
        ("TimeLimit:steps=5", "TimeLimit has no parameter 'steps'"),
        ("TimeLimit:max_episode_steps=0", "is out of range: '0' is not in [1, 100000]"),
        ("Nope:x=1", "unknown wrapper 'Nope'"),
    ],
)
def test_parse_rejects_malformed_text(text: str, fragment: str) -> None:
    with pytest.raises(ValueError) as caught:
        parse_wrapper_spec(text)
    assert fragment in str(caught.value)


# -- building: envs, reprs, errors ------------------------------------------------


def test_repr_reads_like_gymnasium() -> None:
    assert str(build_env(GRID)) == (
        "<TimeLimit<OrderEnforcing<PassiveEnvChecker<GridWorldEnv<tui_gym/GridWorld-v0>>>>>"
    )
    env = build_env(
        "Blackjack-v1",
        choices=[W("TimeLimit", max_episode_steps=5), W("ScaleReward"), W("StepPenalty")],
    )
    assert repr(env) == (
        "<StepPenalty<ScaleReward<TimeLimit<OrderEnforcing<PassiveEnvChecker"
        "<BlackjackEnv<Blackjack-v1>>>>>>>"
    )


def test_spec_records_custom_wrappers_so_gym_make_rebuilds_the_stack() -> None:
    choices = [
        W("TimeLimit", max_episode_steps=40),
        W("TimeAwareObservation"),
        W("StepPenalty", penalty=0.5),
        W("DistanceShaping", k=0.2),
    ]
    env = build_env(GRID, choices=choices)
    rebuilt = gym.make(env.spec)
    assert str(rebuilt) == str(env)
    assert rebuilt.spec.max_episode_steps == 40
    obs_a, _ = env.reset(seed=5)
    obs_b, _ = rebuilt.reset(seed=5)
    np.testing.assert_array_equal(obs_a, obs_b)
    assert env.step(UP)[1] == rebuilt.step(UP)[1]


def test_unknown_env_gets_a_short_message_with_suggestions() -> None:
    with pytest.raises(UnknownEnvError) as caught:
        build_env("blackjack-v1")
    message = str(caught.value)
    assert message.startswith("unknown environment 'blackjack-v1'; did you mean 'Blackjack-v1'")
    assert "\n" not in message
    assert isinstance(caught.value, ValueError)
    with pytest.raises(UnknownEnvError, match=r"^unknown environment 'NoSuchThing-v0'$"):
        build_env("NoSuchThing-v0")
    with pytest.raises(UnknownEnvError, match="did you mean 'tui_gym/GridWorld-v0'"):
        build_env("tui_gym/Gridworld-v0")


def test_an_id_only_a_newer_version_of_is_registered_gets_the_same_short_message(
        monkeypatch) -> None:
    # (as Taxi-v3 once Gymnasium has Taxi-v4: gymnasium raised DeprecatedEnv, a traceback)
    import gymnasium as gym

    monkeypatch.setitem(gym.registry, "TuiGymOld-v2",
                        gym.envs.registration.EnvSpec("TuiGymOld-v2", entry_point="no:such"))
    with pytest.raises(UnknownEnvError, match=r"^unknown environment 'TuiGymOld-v1'; did you "
                       r"mean 'TuiGymOld-v2'\?$"):
        build_env("TuiGymOld-v1")


def test_build_env_rejects_unknown_wrappers_and_misfits() -> None:
    with pytest.raises(UnknownWrapperError):
        build_env("Blackjack-v1", choices=[WrapperChoice("FrameSkip")])
    with pytest.raises(ValueError, match=r"TimeLimit.max_episode_steps is out of range"):
        build_env("Blackjack-v1", choices=[WrapperChoice("TimeLimit", (("max_episode_steps", 0),))])
    with pytest.raises(WrapperMismatchError) as caught:
        build_env("Blackjack-v1", choices=[W("ScaleReward"), W("DistanceShaping")])
    assert caught.value.reason == (
        "DistanceShaping needs an env that reports info['distance'] each step; Blackjack-v1 does "
        "not"
    )
    assert caught.value.choice == W("DistanceShaping")


def test_time_aware_needs_a_time_limit_first() -> None:
    spec = CATALOG["TimeAwareObservation"]
    blackjack = gym.make("Blackjack-v1")
    assert spec.fits(blackjack) == (
        "TimeAwareObservation needs a time limit: add TimeLimit before it (Blackjack-v1 has none)"
    )
    assert spec.fits(gym.make(GRID)) is None  # registered with max_episode_steps=300
    with pytest.raises(WrapperMismatchError, match="add TimeLimit before it"):
        spec.build(blackjack)
    env = build_env("Blackjack-v1", choices=[W("TimeLimit", max_episode_steps=3), W(spec.name)])
    assert env.observation_space.shape == (32 + 11 + 2 + 1,)


def test_lenient_build_skips_misfits_and_says_why() -> None:
    choices = [
        W("DistanceShaping"),
        W("TimeAwareObservation"),
        W("TimeLimit", max_episode_steps=5),
        WrapperChoice("ScaleReward", (("factor", 1000.0),)),
        W("StepPenalty"),
    ]
    env, skipped = build_env_lenient("Blackjack-v1", choices=choices)
    assert str(env) == (
        "<StepPenalty<TimeLimit<OrderEnforcing<PassiveEnvChecker<BlackjackEnv<Blackjack-v1>>>>>>"
    )
    assert [choice.name for choice, _ in skipped] == [
        "DistanceShaping",
        "TimeAwareObservation",
        "ScaleReward",
    ]
    reasons = [reason for _, reason in skipped]
    assert "DistanceShaping needs an env that reports" in reasons[0]
    assert "add TimeLimit before it" in reasons[1]
    assert "ScaleReward.factor is out of range: 1000.0 is not in [-100, 100]" in reasons[2]

    verdicts = check_choices("Blackjack-v1", None, choices)
    assert [choice for choice, _ in verdicts] == choices
    assert [reason is None for _, reason in verdicts] == [False, False, True, False, True]


def test_check_choices_with_time_limit_after_another_wrapper() -> None:
    # A later TimeLimit cannot lengthen GridWorld's registered 300 steps.
    verdicts = check_choices(GRID, None, [W("StepPenalty"), W("TimeLimit", max_episode_steps=500)])
    assert verdicts[0][1] is None
    assert verdicts[1][1] == (
        "TimeLimit of 500 steps cannot lengthen the 300-step limit of tui_gym/GridWorld-v0 "
        "from outside other wrappers: put TimeLimit first, or choose at most 300"
    )
    assert check_choices(GRID, None, [W("StepPenalty"), W("TimeLimit")])[1][1] is None


FIT_ENVS = ["Blackjack-v1", GRID, "FrozenLake-v1"]


@pytest.mark.parametrize("env_id", FIT_ENVS)
@pytest.mark.parametrize("name", list(CATALOG))
def test_every_wrapper_builds_where_it_fits_and_passes_the_checker(env_id: str, name: str) -> None:
    choices = [W("TimeLimit", max_episode_steps=200), W(name)]
    if name == "DistanceShaping" and env_id != GRID:
        verdict = check_choices(env_id, None, choices)[1][1]
        assert verdict is not None and env_id in verdict
        return
    env = build_env(env_id, choices=choices)
    assert type(env).__name__ == name
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    problems = [
        str(w.message) for w in caught if "different from the unwrapped" not in str(w.message)
    ]
    assert problems == []


# -- each wrapper's effect --------------------------------------------------------


def _run_into_wall(env: gym.Env, steps: int) -> list[bool]:
    place(env, agent=(0, 0), target=(4, 4))
    return [env.step(LEFT)[3] for _ in range(steps)]


def test_time_limit_truncates_at_n() -> None:
    env = build_env(GRID, choices=[W("TimeLimit", max_episode_steps=7)])
    assert _run_into_wall(env, 7) == [False] * 6 + [True]


def test_time_limit_first_replaces_the_registered_limit() -> None:
    env = build_env(GRID, choices=[W("TimeLimit", max_episode_steps=320)])
    assert str(env).count("TimeLimit") == 1
    assert env.spec.max_episode_steps == 320
    truncated = _run_into_wall(env, 320)
    assert truncated.index(True) == 319


def test_time_limit_on_a_time_limit_replaces_it() -> None:
    env = build_env(
        "Blackjack-v1",
        choices=[W("TimeLimit", max_episode_steps=50), W("TimeLimit", max_episode_steps=80)],
    )
    assert str(env).count("TimeLimit") == 1
    assert env.spec.max_episode_steps == 80


def test_time_limit_later_only_shortens() -> None:
    env = build_env(GRID, choices=[W("StepPenalty"), W("TimeLimit", max_episode_steps=4)])
    assert _run_into_wall(env, 4) == [False, False, False, True]


def test_flatten_gives_a_1d_array() -> None:
    grid = build_env(GRID, choices=[W("FlattenObservation")])
    obs = place(grid, agent=(1, 2), target=(3, 4))
    assert obs.ndim == 1
    assert obs.tolist() == [1, 2, 3, 4]

    blackjack = build_env("Blackjack-v1", choices=[W("FlattenObservation")])
    obs, _ = blackjack.reset(seed=0)
    assert obs.shape == (32 + 11 + 2,)
    assert obs.sum() == 3  # one-hot: one cell for each of the three parts


def test_time_aware_adds_the_step_count() -> None:
    env = build_env(GRID, choices=[W("TimeAwareObservation")])
    obs = place(env, agent=(0, 0), target=(4, 4))
    assert obs.tolist() == [0, 0, 4, 4, 0]
    assert [env.step(LEFT)[0][-1] for _ in range(3)] == [1, 2, 3]

    as_dict = build_env(GRID, choices=[W("TimeAwareObservation", flatten=False)])
    obs = place(as_dict, agent=(0, 0), target=(4, 4))
    assert set(obs) == {"agent", "target", "time"}
    assert as_dict.step(LEFT)[0]["time"].tolist() == [1]

    normalized = build_env(
        GRID,
        choices=[
            W("TimeLimit", max_episode_steps=8),
            W("TimeAwareObservation", normalize_time=True),
        ],
    )
    place(normalized, agent=(0, 0), target=(4, 4))
    normalized.step(LEFT)
    assert normalized.step(LEFT)[0][-1] == pytest.approx(2 / 8)


def test_time_aware_on_blackjack_tuple_appends_an_array() -> None:
    env = build_env(
        "Blackjack-v1",
        choices=[W("TimeLimit", max_episode_steps=5), W("TimeAwareObservation", flatten=False)],
    )
    obs, _ = env.reset(seed=1)
    plain, _ = gym.make("Blackjack-v1").reset(seed=1)
    assert len(obs) == 4 and obs[:3] == plain
    assert obs[3].tolist() == [0]


def _sticky_repeat_fraction(p: float, trials: int) -> float:
    """How often the step after `right` moves right again although `left` was asked."""
    env = build_env(GRID, {"size": 9}, [W("StickyAction", repeat_action_probability=p)])
    repeats = 0
    for seed in range(trials):
        place(env, agent=(4, 4), target=(0, 0), seed=seed)
        env.step(RIGHT)
        obs = env.step(LEFT)[0]
        repeats += int(obs["agent"][0] == 6)
    return repeats / trials


def test_sticky_action_repeats_the_previous_action() -> None:
    assert _sticky_repeat_fraction(0.0, 50) == 0.0
    # 200 trials at p = 0.99: the mean is 198 repeats, sd 1.4; 190 is over 5 sd below.
    assert _sticky_repeat_fraction(0.99, 200) >= 0.95


def test_sticky_action_is_seeded_by_reset() -> None:
    def trajectory(seed: int) -> list[tuple[int, ...]]:
        env = build_env(GRID, {"size": 9}, [W("StickyAction", repeat_action_probability=0.5)])
        obs, _ = env.reset(seed=seed)
        actions = np.random.default_rng(0).integers(0, 4, size=60)
        out = [tuple(obs["agent"])]
        for action in actions:
            obs, _, terminated, _, _ = env.step(int(action))
            out.append(tuple(obs["agent"]))
            if terminated:
                obs, _ = env.reset()
        return out

    assert trajectory(3) == trajectory(3)
    assert trajectory(3) != trajectory(4)


def test_delay_returns_zeros_then_the_past() -> None:
    delayed = build_env(GRID, choices=[W("DelayObservation", delay=2)])
    plain = build_env(GRID)
    seen = [place(delayed, agent=(2, 2), target=(4, 4))]
    truth = [place(plain, agent=(2, 2), target=(4, 4))]
    for action in (UP, RIGHT, UP):
        seen.append(delayed.step(action)[0])
        truth.append(plain.step(action)[0])
    for obs in seen[:2]:
        assert obs["agent"].tolist() == [0, 0] and obs["target"].tolist() == [0, 0]
    for obs, past in zip(seen[2:], truth, strict=False):
        assert obs["agent"].tolist() == past["agent"].tolist()

    lake = build_env("FrozenLake-v1", choices=[W("DelayObservation", delay=1)])
    assert lake.reset(seed=0)[0] == 0


def _grid_rewards(choice: WrapperChoice, **env_kwargs: Any) -> list[float]:
    """Rewards for: bump the wall, then walk (0,0) -> (2,0) onto the target."""
    env = build_env(GRID, env_kwargs, [choice])
    place(env, agent=(0, 0), target=(2, 0))
    return [float(env.step(action)[1]) for action in (LEFT, RIGHT, RIGHT)]


def test_clip_reward_clips() -> None:
    choice = W("ClipReward", min_reward=-1, max_reward=2)
    rewards = _grid_rewards(choice, reward_scale=5.0, step_penalty=3.0)
    assert rewards == [-1.0, -1.0, 2.0]


def test_scale_reward_scales() -> None:
    rewards = _grid_rewards(W("ScaleReward", factor=-4), step_penalty=0.5)
    assert rewards == [2.0, 2.0, -4.0]


def test_step_penalty_subtracts_from_every_step() -> None:
    assert _grid_rewards(W("StepPenalty", penalty=0.25)) == [-0.25, -0.25, 0.75]

    penalized = build_env("Blackjack-v1", choices=[W("StepPenalty", penalty=0.5)])
    plain = build_env("Blackjack-v1")
    for seed in range(20):
        penalized.reset(seed=seed)
        plain.reset(seed=seed)
        assert penalized.step(0)[1] == plain.step(0)[1] - 0.5


def test_distance_shaping_adds_minus_k_distance() -> None:
    env = build_env(GRID, choices=[W("DistanceShaping", k=0.5)])
    place(env, agent=(0, 0), target=(3, 0))
    steps = [env.step(action) for action in (LEFT, RIGHT, RIGHT, RIGHT)]
    assert [s[4]["distance"] for s in steps] == [3, 2, 1, 0]
    assert [s[1] for s in steps] == [-1.5, -1.0, -0.5, 1.0]
    assert steps[-1][2] is True


def test_distance_shaping_refuses_envs_without_distance() -> None:
    spec = CATALOG["DistanceShaping"]
    assert spec.fits(gym.make("Blackjack-v1")) == (
        "DistanceShaping needs an env that reports info['distance'] each step; Blackjack-v1 does "
        "not"
    )
    assert spec.fits(gym.make("gymnasium_env/GridWorld-v0")) is None


# -- the length of a chain ------------------------------------------------------


def test_a_chain_longer_than_the_cap_is_refused_wherever_it_comes_from(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.test_storage import _with_meta
    from tui_gym.cli import main
    from tui_gym.core.wrappers import MAX_CHAIN
    from tui_gym.session.session import Session
    from tui_gym.session.storage import StorageError

    delay = W("DelayObservation")
    build_env(GRID, choices=[delay] * MAX_CHAIN).close()
    too_many = f"a chain of {MAX_CHAIN + 1} wrappers: a chain holds at most {MAX_CHAIN}"
    for build in (build_env, build_env_lenient, check_choices):
        with pytest.raises(ValueError, match=too_many):
            build(GRID, None, [delay] * (MAX_CHAIN + 1))
    assert main(["train", "blackjack", *["--wrapper=DelayObservation"] * 2_000]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a chain of 2,000 wrappers" in err
    # A save file that names 2,000 of them.
    path = tmp_path / "agent.tgym"
    Session("blackjack").save(path)
    path.write_bytes(_with_meta(path.read_bytes(), wrappers=["DelayObservation"] * 2_000))
    with pytest.raises(StorageError, match="wrappers is not valid: a chain of 2,000 wrappers"):
        Session.load(path)
