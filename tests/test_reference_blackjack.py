"""Tests for `tui_gym.games.blackjack.solver`: the exact Blackjack DP.

Three independent yardsticks: Sutton & Barto's published optimal strategy; an
exact evaluator written here on Gymnasium's own hand functions and its own
`step` rewards; and Monte-Carlo runs of ``gym.make("Blackjack-v1")`` with
bounds from the sample size.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import cache
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.toy_text import blackjack as gym_bj

from tui_gym.games.blackjack.solver import (
    HIT,
    POLICY_SHAPE,
    STICK,
    BlackjackRules,
    optimal_action_values,
    optimal_policy,
    optimal_value,
    policy_value,
)

PLAIN = BlackjackRules()
NATURAL = BlackjackRules(natural=True)
SAB = BlackjackRules(sab=True)
ALL_RULES = (PLAIN, NATURAL, SAB)
RULE_IDS = ("plain", "natural", "sab")

# The states where the player decides, written out on their own: hard totals 4..21 and
# soft totals 12..21, each against a dealer's card 1..10.
DECISION_MASK = np.zeros(POLICY_SHAPE, dtype=bool)
DECISION_MASK[4:22, 1:11, 0] = True
DECISION_MASK[12:22, 1:11, 1] = True


def policy_from_function(fn: Callable[[int, int, int], int]) -> np.ndarray:
    """A policy array from ``fn(player_sum, dealer_card, usable_ace) -> 0 | 1``.

    ``fn`` is called once per decision state (`DECISION_MASK`); other entries are 0.
    """
    policy = np.zeros(POLICY_SHAPE, dtype=np.int8)
    for player_sum, dealer_card, usable_ace in zip(*np.nonzero(DECISION_MASK), strict=True):
        action = fn(int(player_sum), int(dealer_card), int(usable_ace))
        if action not in (STICK, HIT):
            raise ValueError(
                f"fn({player_sum}, {dealer_card}, {usable_ace}) returned {action!r}, not 0 or 1"
            )
        policy[player_sum, dealer_card, usable_ace] = int(action)
    return policy

CARD_PROBS = {card: (4 if card == 10 else 1) / 13 for card in range(1, 11)}

# Sutton & Barto, "Reinforcement Learning: An Introduction", 2nd ed. (2018),
# Figure 5.2: the optimal policy pi* for the blackjack of Example 5.1 (the
# rules of Blackjack-v1 with sab=True), found there by Monte Carlo ES.
# Transcribed from the figure: rows are the player's sum, 21 down to 12;
# columns the dealer's showing card A, 2, ..., 10. S = stick, H = hit.
SAB_FIGURE_5_2_USABLE_ACE = """
21 SSSSSSSSSS
20 SSSSSSSSSS
19 SSSSSSSSSS
18 HSSSSSSSHH
17 HHHHHHHHHH
16 HHHHHHHHHH
15 HHHHHHHHHH
14 HHHHHHHHHH
13 HHHHHHHHHH
12 HHHHHHHHHH
"""
SAB_FIGURE_5_2_NO_USABLE_ACE = """
21 SSSSSSSSSS
20 SSSSSSSSSS
19 SSSSSSSSSS
18 SSSSSSSSSS
17 SSSSSSSSSS
16 HSSSSSHHHH
15 HSSSSSHHHH
14 HSSSSSHHHH
13 HSSSSSHHHH
12 HHHSSSHHHH
"""


def _parse_chart(chart: str) -> dict[tuple[int, int], int]:
    """{(player_sum, dealer_card): action} from a chart's text."""
    out = {}
    for line in chart.strip().splitlines():
        total, row = line.split()
        assert len(row) == 10
        for dealer_card, mark in zip(range(1, 11), row, strict=True):
            out[int(total), dealer_card] = {"S": STICK, "H": HIT}[mark]
    return out


# -- simple policies -----------------------------------------------------------


def threshold_policy(stick_from: int) -> np.ndarray:
    return policy_from_function(lambda s, d, u: int(s < stick_from))


NEVER_HIT = policy_from_function(lambda s, d, u: STICK)
ALWAYS_HIT = policy_from_function(lambda s, d, u: HIT)
STICK_ON_20 = threshold_policy(20)


def random_policy(rng: np.random.Generator) -> np.ndarray:
    return np.where(DECISION_MASK, rng.integers(0, 2, POLICY_SHAPE), 0).astype(np.int8)


# -- an independent exact evaluator on Gymnasium's own code ------------------


@cache
def dealer_finals(up: int) -> tuple[tuple[tuple[int, ...], float], ...]:
    """The dealer's final hands given the up card, one representative hand per
    (score, is natural), with probabilities; by gym's `sum_hand` stopping rule."""

    @cache
    def finish(hand: tuple[int, ...]) -> dict[tuple[int, bool], tuple[tuple[int, ...], float]]:
        if gym_bj.sum_hand(list(hand)) >= 17:
            return {(gym_bj.score(list(hand)), gym_bj.is_natural(list(hand))): (hand, 1.0)}
        out: dict[tuple[int, bool], tuple[tuple[int, ...], float]] = {}
        for card, p in CARD_PROBS.items():
            for key, (rep, q) in finish(tuple(sorted((*hand, card)))).items():
                old_rep, old_q = out.get(key, (rep, 0.0))
                out[key] = (old_rep, old_q + p * q)
        return out

    total: dict[tuple[int, bool], tuple[tuple[int, ...], float]] = {}
    for hole, p in CARD_PROBS.items():
        for key, (rep, q) in finish(tuple(sorted((up, hole)))).items():
            old_rep, old_q = total.get(key, (rep, 0.0))
            total[key] = (old_rep, old_q + p * q)
    return tuple(total.values())


@cache
def raw_env(rules: BlackjackRules) -> gym_bj.BlackjackEnv:
    env = gym_bj.BlackjackEnv(**rules.env_kwargs())
    env.reset(seed=0)
    return env


@cache
def gym_reward(rules: BlackjackRules, player: tuple[int, ...], dealer: tuple[int, ...]) -> float:
    """Gym's own reward for sticking with these hands (the dealer's hand is final)."""
    env = raw_env(rules)
    env.player, env.dealer = list(player), list(dealer)
    _, reward, terminated, _, _ = env.step(STICK)
    assert terminated
    return float(reward)


def exact_value_via_gym(policy: np.ndarray, rules: BlackjackRules) -> float:
    """Expected return of ``policy`` by recursion over explicit hands.

    Hands grow with gym's card values; gym's `sum_hand` / `usable_ace` give the
    observation, `is_bust` the end, and gym's `step` the pay-off. A hand's future
    depends on it only through (sum, usable ace, natural), which keys the memo.
    """
    value = 0.0
    for up, p_up in CARD_PROBS.items():
        finals = dealer_finals(up)

        def stick_value(hand: tuple[int, ...], finals=finals) -> float:
            return sum(q * gym_reward(rules, tuple(sorted(hand)), rep) for rep, q in finals)

        memo: dict[tuple[int, int, bool], float] = {}

        def play(hand: tuple[int, ...], up=up, memo=memo, stick_value=stick_value) -> float:
            cards = list(hand)
            key = (gym_bj.sum_hand(cards), gym_bj.usable_ace(cards), gym_bj.is_natural(cards))
            if key not in memo:
                if policy[key[0], up, key[1]] == STICK:
                    memo[key] = stick_value(hand)
                else:
                    memo[key] = sum(
                        p * (-1.0 if gym_bj.is_bust([*cards, c]) else play((*hand, c)))
                        for c, p in CARD_PROBS.items()
                    )
            return memo[key]

        for c1, p1 in CARD_PROBS.items():
            for c2, p2 in CARD_PROBS.items():
                value += p_up * p1 * p2 * play((c1, c2))
    return value


def initial_observation_probs() -> dict[tuple[int, int, int], float]:
    """P(first observation) from gym's deal: dealer's first card shows."""
    probs: dict[tuple[int, int, int], float] = {}
    for up, p_up in CARD_PROBS.items():
        for c1, p1 in CARD_PROBS.items():
            for c2, p2 in CARD_PROBS.items():
                hand = [c1, c2]
                obs = (gym_bj.sum_hand(hand), up, gym_bj.usable_ace(hand))
                probs[obs] = probs.get(obs, 0.0) + p_up * p1 * p2
    return probs


# -- the published strategy ----------------------------------------------------


def test_sab_optimal_policy_matches_sutton_barto_figure_5_2() -> None:
    policy = optimal_policy(SAB)
    for usable, chart in ((1, SAB_FIGURE_5_2_USABLE_ACE), (0, SAB_FIGURE_5_2_NO_USABLE_ACE)):
        expected = _parse_chart(chart)
        got = {key: int(policy[key[0], key[1], usable]) for key in expected}
        wrong = sorted(key for key in expected if got[key] != expected[key])
        assert not wrong, f"usable_ace={usable}: differs from Figure 5.2 at {wrong}"


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_optimal_policy_shape_and_low_hard_totals(rules: BlackjackRules) -> None:
    policy = optimal_policy(rules)
    assert policy.shape == POLICY_SHAPE and policy.dtype == np.int8
    assert set(np.unique(policy)) <= {STICK, HIT}
    assert (policy[~DECISION_MASK] == STICK).all()
    # A hard total of 11 or less cannot bust, and a stick only gains from a higher total.
    assert (policy[4:12, 1:, 0] == HIT).all()
    assert (policy[21, 1:, :] == STICK).all()


# -- exact values ---------------------------------------------------------------


def test_optimal_values_of_the_three_rule_sets() -> None:
    # The figure for the default rules is about -0.0466.
    assert optimal_value(PLAIN) == pytest.approx(-0.0466, abs=5e-5)
    # A 1.5 natural only adds; S&B's rule adds less (a natural already wins mostly).
    assert optimal_value(PLAIN) < optimal_value(SAB) < optimal_value(NATURAL)


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_policy_value_of_the_optimal_policy_is_the_optimal_value(rules: BlackjackRules) -> None:
    assert policy_value(optimal_policy(rules), rules) == pytest.approx(
        optimal_value(rules), abs=1e-12
    )


def test_always_hit_loses_every_hand() -> None:
    # Hitting at every total, 21 included, busts every hand sooner or later.
    for rules in ALL_RULES:
        assert policy_value(ALWAYS_HIT, rules) == pytest.approx(-1.0, abs=1e-12)


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_no_policy_beats_the_optimal_one(rules: BlackjackRules) -> None:
    best = optimal_value(rules)
    rng = np.random.default_rng(20240613)
    candidates = [NEVER_HIT, ALWAYS_HIT, *(threshold_policy(t) for t in range(12, 22))]
    candidates += [random_policy(rng) for _ in range(50)]
    # Every one-state deviation from the optimum.
    optimum = optimal_policy(rules)
    for index in zip(*np.nonzero(DECISION_MASK), strict=True):
        flipped = optimum.copy()
        flipped[index] = 1 - flipped[index]
        candidates.append(flipped)
    values = np.array([policy_value(p, rules) for p in candidates])
    assert values.max() <= best + 1e-12
    assert values.min() == pytest.approx(-1.0)


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_policy_value_matches_an_exact_evaluation_on_gyms_own_code(
    rules: BlackjackRules,
) -> None:
    rng = np.random.default_rng(7)
    optimum = optimal_policy(rules)
    hit_on_soft_21 = optimum.copy()
    hit_on_soft_21[21, 1:, 1] = HIT  # also hits the natural, which then stops being one
    policies = {
        "never hit": NEVER_HIT,
        "stick on 20+": STICK_ON_20,
        "optimal": optimum,
        "hit soft 21": hit_on_soft_21,
        "random": random_policy(rng),
    }
    for name, policy in policies.items():
        assert policy_value(policy, rules) == pytest.approx(
            exact_value_via_gym(policy, rules), abs=1e-12
        ), name


def test_never_hit_by_hand_from_the_dealer_distribution() -> None:
    # Below 17 a stick wins exactly when the dealer busts, and loses otherwise.
    bust_vs_2 = sum(q for rep, q in dealer_finals(2) if gym_bj.is_bust(list(rep)))
    stick_12_vs_2 = optimal_action_values(PLAIN)[12, 2, 0, STICK]
    assert stick_12_vs_2 == pytest.approx(bust_vs_2 - (1 - bust_vs_2), abs=1e-12)
    # Under plain rules sticking on any total pays cmp(player, dealer): sum it out.
    probs = initial_observation_probs()
    by_hand = 0.0
    for (total, up, _usable), p in probs.items():
        for rep, q in dealer_finals(up):
            dealer = gym_bj.score(list(rep))
            by_hand += p * q * ((total > dealer) - (total < dealer))
    assert policy_value(NEVER_HIT, PLAIN) == pytest.approx(by_hand, abs=1e-12)


# -- Q* -------------------------------------------------------------------------


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_q_is_defined_exactly_at_decision_states(rules: BlackjackRules) -> None:
    q = optimal_action_values(rules)
    assert q.shape == (*POLICY_SHAPE, 2)
    assert np.isfinite(q[DECISION_MASK]).all()
    assert np.isnan(q[~DECISION_MASK]).all()
    # The policy is Q's argmax (ties to stick), and no decision is a near-tie.
    policy = optimal_policy(rules)
    gap = q[..., HIT] - q[..., STICK]
    assert (policy[DECISION_MASK] == (gap[DECISION_MASK] > 0)).all()
    assert np.abs(gap[DECISION_MASK]).min() > 1e-6


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_deal_value_is_the_initial_weighted_max_of_q(rules: BlackjackRules) -> None:
    # On the deal a soft 21 is always the natural.
    q = optimal_action_values(rules, soft_21="natural")
    value = sum(p * np.max(q[obs]) for obs, p in initial_observation_probs().items())
    assert value == pytest.approx(optimal_value(rules), abs=1e-12)


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_q_satisfies_bellman_with_gyms_hand_arithmetic(rules: BlackjackRules) -> None:
    q = optimal_action_values(rules)
    q_drawn = optimal_action_values(rules, soft_21="drawn")
    v_drawn = q_drawn.max(axis=-1)  # after a hit a soft 21 is never a natural
    # One hand per decision observation, none of them a natural.
    hands = {(t, 0): [2, t - 2] if t <= 11 else [10, t - 10] for t in range(4, 21)}
    hands[21, 0] = [10, 9, 2]
    hands.update({(t, 1): [1, t - 11] if t > 12 else [1, 1] for t in range(12, 21)})
    hands[21, 1] = [1, 5, 5]
    for (total, usable), hand in hands.items():
        assert (gym_bj.sum_hand(hand), gym_bj.usable_ace(hand)) == (total, usable)
        for up in range(1, 11):
            backup = 0.0
            for card, p in CARD_PROBS.items():
                nxt = [*hand, card]
                if gym_bj.is_bust(nxt):
                    backup -= p
                else:
                    backup += p * v_drawn[gym_bj.sum_hand(nxt), up, gym_bj.usable_ace(nxt)]
            assert q_drawn[total, up, usable, HIT] == pytest.approx(backup, abs=1e-12)
            stick = sum(q * gym_reward(rules, tuple(hand), rep) for rep, q in dealer_finals(up))
            assert q_drawn[total, up, usable, STICK] == pytest.approx(stick, abs=1e-12)
            if (total, usable) != (21, 1):
                assert q[total, up, usable] == pytest.approx(q_drawn[total, up, usable])


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_soft_21_observation_mixes_the_natural_and_the_drawn_hand(rules: BlackjackRules) -> None:
    mixed = optimal_action_values(rules)[21, 1:, 1]
    natural = optimal_action_values(rules, soft_21="natural")[21, 1:, 1]
    drawn = optimal_action_values(rules, soft_21="drawn")[21, 1:, 1]
    low, high = np.minimum(natural, drawn), np.maximum(natural, drawn)
    assert ((low - 1e-12 <= mixed) & (mixed <= high + 1e-12)).all()
    # Hitting a natural throws it away: the same hit value as a drawn soft 21.
    np.testing.assert_allclose(natural[:, HIT], drawn[:, HIT], atol=1e-12)
    if rules == PLAIN:
        np.testing.assert_allclose(natural, drawn, atol=1e-12)
    else:
        assert (natural[:, STICK] > drawn[:, STICK]).all()
    with pytest.raises(ValueError):
        optimal_action_values(rules, soft_21="maybe")  # type: ignore[arg-type]


# -- the API around it ----------------------------------------------------------


def test_rules_from_env_kwargs() -> None:
    assert BlackjackRules.from_env_kwargs({}) == PLAIN
    assert BlackjackRules.from_env_kwargs({"natural": True, "render_mode": None}) == NATURAL
    assert BlackjackRules.from_env_kwargs({"sab": True}) == SAB
    assert BlackjackRules.from_env_kwargs(NATURAL.env_kwargs()) == NATURAL
    # sab overrides natural, in the env and here.
    both = BlackjackRules(natural=True, sab=True)
    assert optimal_value(both) == optimal_value(SAB)


def test_policy_from_function_and_validation() -> None:
    calls = []

    def fn(s: int, d: int, u: int) -> int:
        calls.append((s, d, u))
        return int(s < 17)

    policy = policy_from_function(fn)
    assert len(calls) == int(DECISION_MASK.sum()) == (18 + 10) * 10
    assert all(isinstance(v, int) for call in calls for v in call)
    assert policy[16, 10, 0] == HIT and policy[17, 10, 0] == STICK and policy[3, 1, 0] == STICK
    with pytest.raises(ValueError):
        policy_from_function(lambda s, d, u: 2)
    with pytest.raises(ValueError):
        policy_value(np.zeros((32, 11)))
    bad = NEVER_HIT.copy()
    bad[15, 3, 0] = 5
    with pytest.raises(ValueError):
        policy_value(bad)
    junk = NEVER_HIT.copy()
    junk[~DECISION_MASK] = 7  # never read
    assert policy_value(junk) == policy_value(NEVER_HIT)


def test_results_are_fresh_arrays() -> None:
    optimal_policy(PLAIN)[12, 2, 0] = 9
    optimal_action_values(PLAIN)[12, 2, 0, 0] = 9.0
    assert optimal_policy(PLAIN)[12, 2, 0] == HIT
    assert optimal_action_values(PLAIN)[12, 2, 0, 0] != 9.0


# -- Monte Carlo against the real env ---------------------------------------------


class BulkChoice:
    """Stands in for the env's ``np_random``: ``choice(seq)`` picks uniformly from
    ``seq`` like numpy's, but from uniforms drawn in bulk. Gym's game code runs
    unchanged; only the source of its coin flips is faster."""

    def __init__(self, seed: int, batch: int = 1 << 16) -> None:
        self._rng = np.random.default_rng(seed)
        self._batch = batch
        self._refill()

    def _refill(self) -> None:
        self._uniforms = self._rng.random(self._batch).tolist()
        self._next = 0

    def choice(self, seq: Sequence[Any]) -> Any:
        if self._next == self._batch:
            self._refill()
        u = self._uniforms[self._next]
        self._next += 1
        return seq[int(u * len(seq))]


def play_episodes(
    policy: np.ndarray, rules: BlackjackRules, n: int, seed: int, bulk: bool = True
) -> np.ndarray:
    env = gym.make("Blackjack-v1", **rules.env_kwargs())
    env.reset(seed=seed)
    if bulk:
        env.unwrapped.np_random = BulkChoice(seed)
    returns = np.empty(n)
    for i in range(n):
        (total, up, usable), _ = env.reset()
        ret, done = 0.0, False
        while not done:
            (total, up, usable), reward, terminated, truncated, _ = env.step(
                int(policy[total, up, usable])
            )
            ret += reward
            done = terminated or truncated
        returns[i] = ret
    env.close()
    return returns


MC_CASES = [
    # (label, policy, rules, episodes); a blackjack return's sd is about 0.95.
    ("optimal plain", optimal_policy(PLAIN), PLAIN, 40_000),
    ("optimal natural", optimal_policy(NATURAL), NATURAL, 25_000),
    ("optimal sab", optimal_policy(SAB), SAB, 25_000),
    ("stick on 20+", STICK_ON_20, PLAIN, 15_000),
    ("never hit natural", NEVER_HIT, NATURAL, 15_000),
]


@pytest.mark.parametrize(
    ("policy", "rules", "n"), [case[1:] for case in MC_CASES], ids=[c[0] for c in MC_CASES]
)
def test_monte_carlo_agrees_with_the_exact_value(
    policy: np.ndarray, rules: BlackjackRules, n: int
) -> None:
    returns = play_episodes(policy, rules, n, seed=n)
    bound = 4 * returns.std(ddof=1) / math.sqrt(n)  # 4 standard errors: p < 1e-4 by chance
    assert abs(returns.mean() - policy_value(policy, rules)) < bound


def test_monte_carlo_with_gyms_own_random_generator() -> None:
    n = 5_000
    returns = play_episodes(optimal_policy(PLAIN), PLAIN, n, seed=11, bulk=False)
    bound = 4 * returns.std(ddof=1) / math.sqrt(n)
    assert abs(returns.mean() - optimal_value(PLAIN)) < bound
