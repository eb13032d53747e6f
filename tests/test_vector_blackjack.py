"""Tests for `tui_gym.games.blackjack.batched`: batched Blackjack plays Gymnasium's rules.

Three yardsticks: Gymnasium's own env fed the same cards (every observation
and reward equal, step for step); the exact values of `policy_value` for
several fixed policies under every rule set; and Gymnasium's `Blackjack-v1`
resets for the distribution of starting states. Statistical bounds come from
the sample sizes (4 standard errors, or a chi-square quantile at z = 4.5).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from functools import cache

import numpy as np
import pytest
from gymnasium.envs.toy_text import blackjack as gym_bj

from tui_gym.games.blackjack.batched import BatchedBlackjack
from tui_gym.games.blackjack.solver import (
    DECISION_MASK,
    HIT,
    STICK,
    BlackjackRules,
    optimal_policy,
    policy_from_function,
    policy_value,
)

PLAIN = BlackjackRules()
NATURAL = BlackjackRules(natural=True)
SAB = BlackjackRules(sab=True)
ALL_RULES = (PLAIN, NATURAL, SAB)
RULE_IDS = ("plain", "natural", "sab")

CARD_PROBS = {card: (4 if card == 10 else 1) / 13 for card in range(1, 11)}
Z = 4.0  # standard errors allowed: p < 1e-4 per comparison by chance


def chi2_bound(df: int, z: float = 4.5) -> float:
    """The upper z-sigma quantile of chi-square(df), by the Wilson-Hilferty approximation."""
    c = 2.0 / (9.0 * df)
    return df * (1.0 - c + z * math.sqrt(c)) ** 3


# --- the same cards for both envs ---------------------------------------------


class _CardStream:
    """Card values from a list, handed out in order."""

    def __init__(self, cards: list[int]) -> None:
        self._cards: Iterator[int] = iter(cards)

    def next(self) -> int:
        return next(self._cards)


class _GymFakeRandom:
    """Stands in for the scalar env's `np_random`: deck draws come from the stream."""

    def __init__(self, stream: _CardStream) -> None:
        self.stream = stream

    def choice(self, options):  # noqa: ANN001, ANN201 - mimics Generator.choice
        if list(options) == gym_bj.deck:
            return self.stream.next()
        return options[0]  # card suits and faces: cosmetic


class _BatchedFakeRandom:
    """Stands in for the batched env's generator: `integers` come from the stream."""

    def __init__(self, stream: _CardStream) -> None:
        self.stream = stream

    def integers(self, low: int, high: int, size: int | tuple[int, ...]) -> np.ndarray:
        assert (low, high) == (1, 14)
        shape = (size,) if isinstance(size, int) else size
        return np.array([self.stream.next() for _ in range(math.prod(shape))]).reshape(shape)


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
def test_same_cards_same_game_as_gymnasium(rules: BlackjackRules) -> None:
    """Dealt the same cards and given the same actions, both envs agree on everything."""
    rng = np.random.default_rng(7)
    faces = np.arange(1, 11)
    probs = np.array([CARD_PROBS[c] for c in faces])
    scalar = gym_bj.BlackjackEnv(natural=rules.natural, sab=rules.sab)
    batched = BatchedBlackjack(1, rules)
    naturals = 0
    for _ in range(1500):
        cards = rng.choice(faces, size=40, p=probs).tolist()
        if rng.random() < 0.2:  # deal plenty of naturals, to either side
            first = 2 * int(rng.integers(2))
            cards[first : first + 2] = [1, 10] if rng.random() < 0.5 else [10, 1]
        scalar_stream, batched_stream = _CardStream(cards), _CardStream(cards)
        scalar._np_random = _GymFakeRandom(scalar_stream)
        batched.rng = _BatchedFakeRandom(batched_stream)
        obs, _ = scalar.reset()
        row = batched.reset()[0]
        assert tuple(row) == obs
        naturals += gym_bj.is_natural(scalar.player)
        done = False
        while not done:
            action = int(rng.random() < 0.5)
            obs, reward, terminated, truncated, _ = scalar.step(action)
            result = batched.step(np.array([action]), autoreset=False)
            assert tuple(result.next_obs[0]) == obs
            assert result.reward[0] == reward
            assert bool(result.terminated[0]) == terminated
            assert not result.truncated[0] and not truncated
            done = terminated
    assert naturals > 50


# --- exact values -------------------------------------------------------------


def _stick_always(player: int, dealer: int, usable: int) -> int:
    return STICK


def _stick_from_17(player: int, dealer: int, usable: int) -> int:
    return STICK if player >= 17 else HIT


def _random_policy() -> np.ndarray:
    rng = np.random.default_rng(2024)
    return np.where(DECISION_MASK, rng.integers(0, 2, size=DECISION_MASK.shape), 0).astype(np.int8)


POLICIES = {
    "always_stick": lambda rules: policy_from_function(_stick_always),
    "stick_from_17": lambda rules: policy_from_function(_stick_from_17),
    "optimal": optimal_policy,
    "random_deterministic": lambda rules: _random_policy(),
}


def play_policy(policy: np.ndarray, rules: BlackjackRules, episodes: int, seed: int) -> np.ndarray:
    """The return of each of `episodes` batched games played by a fixed policy."""
    env = BatchedBlackjack(episodes, rules, seed=seed)
    obs = env.reset()
    returns = np.zeros(episodes)
    live = np.arange(episodes)
    while live.size:
        actions = policy[obs[:, 0], obs[:, 1], obs[:, 2]]
        result = env.step(actions, live, autoreset=False)
        returns[live] += result.reward
        going = ~result.done
        live, obs = live[going], result.next_obs[going]
    return returns


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
@pytest.mark.parametrize("name", list(POLICIES))
def test_policy_returns_match_exact_values(name: str, rules: BlackjackRules) -> None:
    policy = POLICIES[name](rules)
    n = 200_000
    seed = list(POLICIES).index(name) * 10 + ALL_RULES.index(rules)
    returns = play_policy(policy, rules, n, seed=seed)
    exact = policy_value(policy, rules)
    standard_error = returns.std(ddof=1) / math.sqrt(n)
    assert abs(returns.mean() - exact) < Z * standard_error, (returns.mean(), exact)


@cache
def _dealer_final(raw: int, has_ace: bool) -> dict[object, float]:
    """The dealer's final total (or "bust") drawing from a hand (aces as 1), not a natural."""
    best = raw + 10 if has_ace and raw <= 11 else raw
    if best > 21:
        return {"bust": 1.0}
    if best >= 17:
        return {best: 1.0}
    out: dict[object, float] = {}
    for card, p in CARD_PROBS.items():
        for end, q in _dealer_final(raw + card, has_ace or card == 1).items():
            out[end] = out.get(end, 0.0) + p * q
    return out


def _expected_stick_21(up: int, rules: BlackjackRules, natural: bool) -> float:
    """Exact mean reward of sticking on 21 (a natural or not) against the up card."""
    dealer_natural = dealer_21 = 0.0
    for hole, p in CARD_PROBS.items():
        if {up, hole} == {1, 10}:
            dealer_natural += p
            dealer_21 += p
        else:
            dealer_21 += p * _dealer_final(up + hole, 1 in (up, hole)).get(21, 0.0)
    if natural and rules.sab:
        return 1.0 - dealer_natural
    win = 1.0 - dealer_21  # 21 beats anything but 21; a tie draws
    return 1.5 * win if natural and rules.natural else win


@pytest.mark.parametrize("rules", ALL_RULES, ids=RULE_IDS)
@pytest.mark.parametrize("natural", [True, False], ids=["natural", "three_card_21"])
def test_sticking_on_21_pays_by_the_rules(rules: BlackjackRules, natural: bool) -> None:
    """Per dealer card: the natural bonus (natural=True) and auto-win (sab=True) are exact."""
    n = 20_000
    for up in range(1, 11):
        env = BatchedBlackjack(n, rules, seed=up)
        env.reset()
        env.dealer_up[:] = up
        env.player_raw[:] = 11  # an ace and a ten, or e.g. A + 5 + 5
        env.player_ace[:] = True
        env.natural[:] = natural
        result = env.step(np.zeros(n, dtype=np.int64), autoreset=False)
        assert result.terminated.all()
        assert (result.next_obs == [21, up, 1]).all()
        expected = _expected_stick_21(up, rules, natural)
        standard_error = max(result.reward.std(ddof=1), 0.1) / math.sqrt(n)
        assert abs(result.reward.mean() - expected) < Z * standard_error, (up, expected)


# --- starting states ----------------------------------------------------------


def _start_cells(obs: np.ndarray) -> np.ndarray:
    """A cell number per start (player sum, usable ace, dealer card)."""
    return (obs[:, 0] * 2 + obs[:, 2]) * 11 + obs[:, 1]


def _exact_start_distribution() -> dict[int, float]:
    probs: dict[int, float] = {}
    for c1, p1 in CARD_PROBS.items():
        for c2, p2 in CARD_PROBS.items():
            usable = int(1 in (c1, c2))
            total = c1 + c2 + 10 * usable
            for up, p3 in CARD_PROBS.items():
                cell = (total * 2 + usable) * 11 + up
                probs[cell] = probs.get(cell, 0.0) + p1 * p2 * p3
    return probs


def test_starts_follow_the_exact_deal() -> None:
    n = 500_000
    env = BatchedBlackjack(n, seed=11)
    cells = _start_cells(env.reset())
    exact = _exact_start_distribution()
    keys = np.array(sorted(exact))
    counts = np.array([np.count_nonzero(cells == k) for k in keys])
    assert counts.sum() == n  # no start outside the exact support
    expected = n * np.array([exact[k] for k in keys])
    chi2 = float(((counts - expected) ** 2 / expected).sum())
    assert chi2 < chi2_bound(len(keys) - 1)


def test_starts_match_gymnasium_resets() -> None:
    """Two-sample chi-square over (player sum, usable ace, dealer card) cells."""
    scalar = gym_bj.BlackjackEnv()
    n_scalar = 20_000
    scalar_obs = np.empty((n_scalar, 3), dtype=np.int64)
    scalar.reset(seed=5)
    for i in range(n_scalar):
        scalar_obs[i] = scalar.reset()[0]
    n_batched = 400_000
    batched_obs = BatchedBlackjack(n_batched, seed=5).reset()
    a, b = _start_cells(scalar_obs), _start_cells(batched_obs)
    keys = np.union1d(a, b)
    count_a = np.array([np.count_nonzero(a == k) for k in keys], dtype=np.float64)
    count_b = np.array([np.count_nonzero(b == k) for k in keys], dtype=np.float64)
    pooled = (count_a + count_b) / (n_scalar + n_batched)
    variance = pooled * (1 / n_scalar + 1 / n_batched)
    chi2 = float(((count_a / n_scalar - count_b / n_batched) ** 2 / variance).sum())
    assert chi2 < chi2_bound(len(keys) - 1)
    for column in range(3):  # and the marginals, one by one
        values = np.union1d(scalar_obs[:, column], batched_obs[:, column])
        for value in values:
            p_a = np.count_nonzero(scalar_obs[:, column] == value) / n_scalar
            p_b = np.count_nonzero(batched_obs[:, column] == value) / n_batched
            p = (p_a * n_scalar + p_b * n_batched) / (n_scalar + n_batched)
            assert abs(p_a - p_b) < Z * math.sqrt(p * (1 - p) * (1 / n_scalar + 1 / n_batched))


# --- mechanics ----------------------------------------------------------------


def test_bust_shows_the_raw_total_and_ends_with_minus_one() -> None:
    env = BatchedBlackjack(2000, seed=3)
    env.reset()
    env.player_raw[:] = 20  # hard 20: any card but an ace busts
    env.player_ace[:] = False
    env.natural[:] = False
    result = env.step(np.ones(2000, dtype=np.int64), autoreset=False)
    bust = result.terminated
    assert 0 < bust.sum() < 2000
    assert (result.reward[bust] == -1.0).all()
    assert (result.next_obs[bust, 0] > 21).all() and (result.next_obs[bust, 0] <= 30).all()
    assert (result.next_obs[bust, 2] == 0).all()
    assert (result.next_obs[~bust, 0] == 21).all()  # an ace: hard 21
    assert (result.next_obs[~bust, 2] == 0).all()
    assert (result.reward[~bust] == 0.0).all()


def test_autoreset_returns_the_final_step_then_the_new_deal() -> None:
    env = BatchedBlackjack(500, seed=9)
    start = env.reset()
    result = env.step(np.zeros(500, dtype=np.int64))  # everyone sticks: every game ends
    assert result.terminated.all()
    assert (result.next_obs == start).all()  # sticking shows the hand it stuck on
    assert (result.obs == env.observations()).all()
    assert (env.elapsed == 0).all()
    assert not (result.obs == start).all()


def test_time_limit_truncates() -> None:
    env = BatchedBlackjack(300, seed=4, max_episode_steps=1)
    env.reset()
    env.player_raw[:] = 4
    env.player_ace[:] = False
    result = env.step(np.ones(300, dtype=np.int64), autoreset=False)
    assert result.truncated.all()
    assert not result.terminated.any()  # from 4 one card never busts


def test_same_seed_same_games_and_subsets_step_alone() -> None:
    a, b = BatchedBlackjack(64, seed=1), BatchedBlackjack(64, seed=1)
    assert (a.reset() == b.reset()).all()
    actions = np.tile([0, 1], 32)
    ra, rb = a.step(actions), b.step(actions)
    assert (ra.obs == rb.obs).all() and (ra.reward == rb.reward).all()

    before, elapsed = a.observations(), a.elapsed.copy()
    index = np.array([3, 10, 40])
    a.step(np.array([0, 0, 0]), index, autoreset=False)
    untouched = np.setdiff1d(np.arange(64), index)
    assert (a.observations(untouched) == before[untouched]).all()
    assert (a.elapsed[untouched] == elapsed[untouched]).all()
    assert (a.elapsed[index] == elapsed[index] + 1).all()


def test_bad_actions_are_rejected() -> None:
    env = BatchedBlackjack(4, seed=0)
    env.reset()
    with pytest.raises(ValueError):
        env.step(np.array([0, 1, 2, 0]))
    with pytest.raises(ValueError):
        env.step(np.array([0, 1]))
    with pytest.raises(ValueError):
        BatchedBlackjack(0)
