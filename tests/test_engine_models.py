"""The models the engine trains on are the games as played, and the engine says which loop
trains and why.

Blackjack's model is checked card by card against Gymnasium's own hand arithmetic, its
deal against the exact two-card distribution, sticking against the rules' pay-offs (and
hands played on the real env), and its optimum against the dynamic programme; GridWorld's
model move by move against the env, with the catalog's reward wrappers and time limit
applied by the wrappers' own code. A wrapper chain no model follows trains on the env.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.toy_text.blackjack import sum_hand, usable_ace

from tests.gridworld_support import all_pairs
from tests.test_reference_blackjack import BulkChoice
from tui_gym.core.mdp import solve
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.wrappers import WrapperChoice, build_env
from tui_gym.core.wrappers.changes import NO_CHANGES
from tui_gym.envs.gridworld import GridWorldEnv
from tui_gym.games.blackjack.solver import (
    N_BASE,
    BlackjackRules,
    blackjack_model,
    observation_rows,
    optimal_value,
)
from tui_gym.games.gridworld.paths import gridworld_model
from tui_gym.session.session import Session

RULES = (BlackjackRules(), BlackjackRules(natural=True), BlackjackRules(sab=True))
RULE_IDS = ("plain", "natural", "sab")
CARD_PROBS = {card: (4 if card == 10 else 1) / 13 for card in range(1, 11)}
STICK, HIT = 0, 1
ROWS = observation_rows()  # the table row of each model state
OBSERVATIONS = 32 * 11 * 2  # the observation keyer's rows
KEYER = ObservationKeyer(gym.make("Blackjack-v1").observation_space)


def observation_row(total: int, dealer: int, usable: int) -> int:
    return KEYER.key((total, dealer, usable))


def state_of(total: int, dealer: int, usable: int) -> int:
    """The model state of a hand (not the opening natural)."""
    return int(np.flatnonzero(ROWS[:N_BASE] == observation_row(total, dealer, usable))[0])


def _outcomes(model, state: int, action: int) -> dict[tuple[int, float, bool], float]:
    return {(s, r, t): p for p, s, r, t in model.outcomes(state, action)}


def _hand(total: int, usable: int) -> list[int]:
    """Cards with that total (aces counted best) and a usable ace or not."""
    if usable:
        return [1, total - 11]
    return [10, total - 10] if total > 11 else [2, total - 2]


@pytest.mark.parametrize("rules", RULES, ids=RULE_IDS)
def test_blackjack_hits_follow_gymnasiums_hand_arithmetic(rules: BlackjackRules) -> None:
    model = blackjack_model(rules)
    lose, push = rules.payoffs[0], rules.payoffs[1]
    for total in range(4, 22):
        for usable in (0, 1) if total >= 12 else (0,):
            for dealer in range(1, 11):
                state = state_of(total, dealer, usable)
                expected: dict[tuple[int, float, bool], float] = {}
                for card, p in CARD_PROBS.items():
                    hand = [*_hand(total, usable), card]
                    after, soft = sum_hand(hand), int(usable_ace(hand))
                    bust = after > 21  # the hand ends where it stood
                    key = ((state, lose, True) if bust
                           else (state_of(after, dealer, soft), push, False))
                    expected[key] = expected.get(key, 0.0) + p
                found = _outcomes(model, state, HIT)
                assert found.keys() == expected.keys()
                assert all(found[k] == pytest.approx(v) for k, v in expected.items())
    assert ROWS[N_BASE + 6] == observation_row(21, 7, 1)  # the natural shows as soft 21


def test_a_bust_loses() -> None:
    model = blackjack_model(BlackjackRules())
    state = state_of(20, 5, 0)
    found = _outcomes(model, state, HIT)
    assert found[(state, -1.0, True)] == pytest.approx(12 / 13)
    assert found[(state_of(21, 5, 0), 0.0, False)] == pytest.approx(1 / 13)


def test_the_deal_follows_the_exact_two_card_distribution() -> None:
    model = blackjack_model(BlackjackRules())
    expected = np.zeros(OBSERVATIONS)
    for c1, p1 in CARD_PROBS.items():
        for c2, p2 in CARD_PROBS.items():
            usable = int(1 in (c1, c2))
            for up, p3 in CARD_PROBS.items():
                expected[observation_row(c1 + c2 + 10 * usable, up, usable)] += p1 * p2 * p3
    shown = np.bincount(ROWS, weights=model.initial, minlength=OBSERVATIONS)
    np.testing.assert_allclose(shown, expected, atol=1e-15)


@pytest.mark.parametrize("rules", RULES, ids=RULE_IDS)
def test_sticking_on_21_pays_by_the_rules_as_the_env_does(rules: BlackjackRules) -> None:
    # The opening natural and a soft 21 drawn to look alike; under `natural` and `sab`
    # they pay apart. Hands played on the real env, stuck on 21, agree with the model.
    model = blackjack_model(rules)
    env = gym.make("Blackjack-v1", natural=rules.natural, sab=rules.sab).unwrapped
    env.reset(seed=1)
    env.np_random = BulkChoice(1)  # gym's game code, its coin flips drawn in bulk
    n = 1500
    for natural, state in ((True, N_BASE + 9), (False, state_of(21, 10, 1))):
        mean = sum(p * r for p, _, r, _ in model.outcomes(state, STICK))
        played = []
        for _ in range(n):
            env.reset()
            env.dealer[0] = 10
            env.player = [1, 10] if natural else [1, 5, 5]
            played.append(env.step(STICK)[1])
        error = max(float(np.std(played)), 0.1) / np.sqrt(n)
        assert abs(np.mean(played) - mean) < 4 * error, (natural, mean, np.mean(played))


@pytest.mark.parametrize("rules", RULES, ids=RULE_IDS)
def test_the_blackjack_model_has_the_exact_optimum(rules: BlackjackRules) -> None:
    model = blackjack_model(rules)
    assert solve(model).value == pytest.approx(optimal_value(rules), abs=1e-12)


@pytest.mark.parametrize("size", [2, 3, 5])
@pytest.mark.parametrize("rewards", [(1.0, 0.0), (2.5, 0.1)], ids=["default", "scaled"])
def test_every_gridworld_move_matches_the_env(size: int, rewards: tuple[float, float]) -> None:
    reward_scale, step_penalty = rewards
    model = gridworld_model(size, reward_scale, step_penalty, NO_CHANGES)
    env = GridWorldEnv(size=size, reward_scale=reward_scale, step_penalty=step_penalty)
    keyer = ObservationKeyer(env.observation_space)
    for pair in all_pairs(size):
        for action in range(4):
            obs, _ = env.reset(options={"agent": pair[:2], "target": pair[2:]})
            state = keyer.key(obs)
            after, reward, terminated, _, _ = env.step(action)
            assert _outcomes(model, state, action) == {
                (keyer.key(after), reward, terminated): 1.0}
    starts = model.initial[model.initial > 0]
    assert len(starts) == size**2 * (size**2 - 1) and np.ptp(starts) == 0


WRAPPED = (
    WrapperChoice.make("StepPenalty", penalty=0.05),
    WrapperChoice.make("DistanceShaping", k=0.2),
    WrapperChoice.make("ScaleReward", factor=3.0),
    WrapperChoice.make("ClipReward", min_reward=-0.9, max_reward=2.0),
    WrapperChoice.make("TimeLimit", max_episode_steps=12),
)


def test_the_gridworld_model_follows_the_wrappers_as_built() -> None:
    """Random walks through the catalog's stack: the model pays what the wrappers pay."""
    session = Session("gridworld", env_kwargs={"size": 4, "reward_scale": 2.0},
                      choices=WRAPPED)
    assert session.engine_reason == (
        "model: GridWorld with StepPenalty, DistanceShaping, ScaleReward, ClipReward, "
        "TimeLimit")
    training = session.training
    assert training is not None and training.model.horizon == 12
    env = build_env("tui_gym/GridWorld-v0", {"size": 4, "reward_scale": 2.0}, WRAPPED)
    keyer = ObservationKeyer(env.observation_space)
    rng = np.random.default_rng(8)
    for episode in range(100):
        obs, _ = env.reset(seed=episode)
        done = False
        while not done:
            action = int(rng.integers(4))
            state = keyer.key(obs)
            obs, reward, terminated, truncated, _ = env.step(action)
            ((after, paid, ended),) = _outcomes(training.model, state, action)
            assert (after, ended) == (keyer.key(obs), terminated)
            assert paid == pytest.approx(reward, abs=1e-12)
            done = terminated or truncated


@pytest.mark.parametrize(
    ("game", "choices", "words"),
    [
        ("blackjack", (), "model: Blackjack"),
        ("blackjack", (WrapperChoice.make("StepPenalty"),), "model: Blackjack with StepPenalty"),
        ("blackjack", (WrapperChoice.make("TimeLimit", max_episode_steps=5),),
         "model: Blackjack with TimeLimit"),
        ("gridworld", (WrapperChoice.make("ClipReward"),), "model: GridWorld with ClipReward"),
        ("frozenlake", (), "model: FrozenLake"),
        ("blackjack", (WrapperChoice.make("DelayObservation"),),
         "env: DelayObservation changes the observations"),
        ("blackjack", (WrapperChoice.make("FlattenObservation"),),
         "env: FlattenObservation changes the observations"),
        ("gridworld", (WrapperChoice.make("StickyAction"),),
         "env: StickyAction changes the game beyond what its model follows"),
    ],
)
def test_the_engine_says_which_loop_trains_and_why(game: str, choices: tuple, words: str) -> None:
    session = Session(game, choices=choices)
    assert session.engine_reason.startswith(words), session.engine_reason
    assert (session.trainer.model is not None) == words.startswith("model")


def test_a_chain_no_model_follows_cannot_be_forced_onto_the_model() -> None:
    with pytest.raises(ValueError, match="the model loop cannot train this: StickyAction"):
        Session("blackjack", choices=(WrapperChoice.make("StickyAction"),), engine="model")
    assert Session("frozenlake", engine="env").engine_reason == "env: chosen"


def test_pairs_with_the_same_many_outcomes_share_one_row_of_them() -> None:
    # Jack's car rental: a move's outcomes depend on the cars in the morning only, so its
    # 4,851 pairs read 441 rows of where to and with what probability; each pair's own
    # rewards stay its own.
    from tui_gym.core.engine.loop import ModelArrays
    from tui_gym.games import game_for

    model = game_for("car-rental").base_model({})
    arrays = ModelArrays.of(model)
    k, pairs = arrays.outcomes, model.n_states * model.n_actions
    assert arrays.pair_rows.shape == (pairs,) and arrays.cumulative.size == 441 * k
    shared = {name: getattr(arrays, name).reshape(-1, k)[arrays.pair_rows]
              for name in ("cumulative", "next_state", "terminal")}
    for name, rows in shared.items():
        assert np.array_equal(rows, getattr(model, name).reshape(pairs, k)), name
    assert np.array_equal(arrays.reward.reshape(pairs, k), model.reward.reshape(pairs, k))
    small = ModelArrays.of(game_for("cliffwalking").base_model({}))
    assert np.array_equal(small.pair_rows, np.arange(small.pair_rows.size))
