"""Gymnasium's ``Blackjack-v1`` as a `FiniteMDP`, and its exact figures from that model.

A natural is a hidden state of its own (it pays differently under `natural` and `sab`)
while every policy stays a function of the observation.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any, Literal

import numpy as np

from tui_gym.core.mdp import FiniteMDP, evaluate, solve
from tui_gym.core.mdp.evaluation import backup

__all__ = [
    "BASE_STATES", "DEALERS", "DEFAULT_RULES", "HIT", "N_BASE", "POLICY_SHAPE", "STICK",
    "BlackjackRules", "base_state", "blackjack_model", "mixed_policy_value", "observation_rows",
    "optimal_action_values", "optimal_policy", "optimal_value", "policy_value",
]


# The bare env's step rewards: a loss or bust, a push or a hit, a win, a paid natural.
BARE_PAYOFFS: tuple[float, float, float, float] = (-1.0, 0.0, 1.0, 1.5)


@dataclass(frozen=True)
class BlackjackRules:
    """The reward variant of ``Blackjack-v1``: ``natural`` (a winning two-card 21 pays
    1.5), ``sab`` (Sutton & Barto's: a natural beats all but a dealer natural, for +1),
    and ``payoffs``, what steps of bare reward -1, 0, +1 and +1.5 pay (`with_rewards`)."""

    natural: bool = False
    sab: bool = False
    payoffs: tuple[float, float, float, float] = BARE_PAYOFFS

    def with_rewards(self, reward: Callable[[float], float]) -> BlackjackRules:
        """These rules with every step's reward passed through `reward` (a wrapper's)."""
        payoffs = tuple(float(reward(base)) for base in BARE_PAYOFFS)
        return BlackjackRules(self.natural, self.sab, payoffs)  # type: ignore[arg-type]

    @classmethod
    def from_env_kwargs(cls, kwargs: Mapping[str, Any]) -> BlackjackRules:
        """The rules of ``gym.make("Blackjack-v1", **kwargs)`` (other keys ignored)."""
        return cls(natural=bool(kwargs.get("natural", False)), sab=bool(kwargs.get("sab", False)))

    def env_kwargs(self) -> dict[str, bool]:
        """Keyword arguments for ``gym.make("Blackjack-v1", ...)`` with these rules."""
        return {"natural": self.natural, "sab": self.sab}


DEFAULT_RULES = BlackjackRules()

STICK = 0
HIT = 1
POLICY_SHAPE = (32, 11, 2)
LONGEST_HAND = 20  # steps: 19 hits from two aces to 21 aces-as-one, then a stick or a bust

# Infinite deck: index i holds the probability of a card of value i + 1.
_CARD_PROBS = np.array([1.0] * 9 + [4.0], dtype=np.float64) / 13.0
_CARDS = range(1, 11)

# A hit strictly better than a stick by less than this counts as a tie (-> stick),
# so float rounding in two sums of the same number cannot flip an action.
_TIE_TOLERANCE = 1e-12

# Player states. Hard totals 4..21, soft (usable-ace) totals 12..21, the opening
# natural (observed as a soft 21), and bust. The hidden "still two cards" fact
# matters only for the natural: every other hand's future and pay-off depend on
# its total and whether it holds a usable ace.
_STATE_OBS: list[tuple[int, int]] = (
    [(t, 0) for t in range(4, 22)] + [(t, 1) for t in range(12, 22)] + [(21, 1)]
)
_N_LIVE = len(_STATE_OBS)  # 29 states where the player still decides
_NATURAL = _N_LIVE - 1
_BUST = _N_LIVE
_HARD = {t: i for i, (t, u) in enumerate(_STATE_OBS[:_NATURAL]) if u == 0}
_SOFT = {t: i for i, (t, u) in enumerate(_STATE_OBS[:_NATURAL]) if u == 1}
_SOFT_21 = _SOFT[21]
_STATE_SUM = np.array([t for t, _ in _STATE_OBS], dtype=np.intp)
_STATE_USABLE = np.array([u for _, u in _STATE_OBS], dtype=np.intp)


def _add_card(total: int, soft: bool, card: int) -> int:
    """The state index after drawing ``card`` to a hand of ``total`` (soft or hard)."""
    if soft:
        # Recounting the ace as 1 takes 10 off, so one card never busts a soft hand.
        return _SOFT[total + card] if total + card <= 21 else _HARD[total + card - 10]
    if card == 1 and total + 11 <= 21:
        return _SOFT[total + 11]
    return _HARD[total + card] if total + card <= 21 else _BUST


def _build_hit_matrix() -> np.ndarray:
    """Row s: the distribution of the next state (incl. bust) after hitting from s."""
    matrix = np.zeros((_N_LIVE, _N_LIVE + 1))
    for s, (total, usable) in enumerate(_STATE_OBS):
        for card, p in zip(_CARDS, _CARD_PROBS, strict=True):
            matrix[s, _add_card(total, bool(usable), card)] += p
    return matrix


def _build_initial() -> np.ndarray:
    """The distribution of the player's state after the two-card deal."""
    initial = np.zeros(_N_LIVE)
    for c1, p1 in zip(_CARDS, _CARD_PROBS, strict=True):
        for c2, p2 in zip(_CARDS, _CARD_PROBS, strict=True):
            if {c1, c2} == {1, 10}:
                initial[_NATURAL] += p1 * p2
            elif c1 == 1 or c2 == 1:
                initial[_SOFT[c1 + c2 + 10]] += p1 * p2
            else:
                initial[_HARD[c1 + c2]] += p1 * p2
    return initial


_HIT_MATRIX = _build_hit_matrix()
_INITIAL = _build_initial()

# The model's states: `live * 10 + dealer - 1` per live player state and dealer card, so the
# game's base states (every observation asking for a decision) come first, the naturals last.
DEALERS = 10
N_BASE = _NATURAL * DEALERS
_OBSERVED = (np.repeat(_STATE_SUM, DEALERS), np.tile(np.arange(1, DEALERS + 1), _N_LIVE),
             np.repeat(_STATE_USABLE, DEALERS))  # each model state's (sum, dealer, usable ace)
BASE_STATES = tuple(zip(*(o[:N_BASE].tolist() for o in _OBSERVED), strict=True))


def base_state(total: int, dealer: int, usable: int) -> int:
    """The base state (and model state) of an observation that asks for a decision."""
    return ((_SOFT if usable else _HARD)[total]) * DEALERS + dealer - 1


# ---------------------------------------------------------------------------
# The dealer


# Columns of the dealer's final-hand distribution.
_D17, _D18, _D19, _D20, _D21, _DNAT, _DBUST = range(7)


@cache
def _dealer_draws_from(raw: int, has_ace: bool) -> np.ndarray:
    """Final (17, 18, 19, 20, 21, natural, bust) probabilities from a hand of raw
    (aces as 1) total ``raw`` that is not a natural, the dealer drawing while the
    hand's best total is below 17 (kept: not to be written to)."""
    best = raw + 10 if has_ace and raw + 10 <= 21 else raw
    out = np.zeros(7)
    if best > 21:
        out[_DBUST] = 1.0
    elif best >= 17:
        out[best - 17] = 1.0
    else:
        for card, p in zip(_CARDS, _CARD_PROBS, strict=True):
            out += p * _dealer_draws_from(raw + card, has_ace or card == 1)
    return out


@cache
def _dealer_final() -> np.ndarray:
    """Row ``up - 1``: the dealer's final hand given the up card, over
    (17, 18, 19, 20, 21 drawn, natural, bust). Same for every rule set."""
    table = np.zeros((10, 7))
    for up in _CARDS:
        for hole, p in zip(_CARDS, _CARD_PROBS, strict=True):
            if {up, hole} == {1, 10}:
                table[up - 1, _DNAT] += p
            else:
                table[up - 1] += p * _dealer_draws_from(up + hole, 1 in (up, hole))
    table.setflags(write=False)
    return table


def stick_chances(rules: BlackjackRules) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`[29, 10]` each: the chances that a stick loses, pushes and wins."""
    final = _dealer_final()
    made = np.column_stack([final[:, _D17:_D21], final[:, _D21] + final[:, _DNAT]])
    scores = np.arange(17, 22)
    win = np.empty((_N_LIVE, 10))
    lose = np.empty((_N_LIVE, 10))
    for s in range(_N_LIVE):
        total = _STATE_SUM[s]  # the score of a stick (never bust while deciding)
        # cmp(player, dealer): a bust dealer scores 0, below any standing player.
        win[s] = final[:, _DBUST] + made[:, scores < total].sum(axis=1)
        lose[s] = made[:, scores > total].sum(axis=1)
    if rules.sab:  # a natural beats every dealer hand but a natural
        win[_NATURAL], lose[_NATURAL] = 1.0 - final[:, _DNAT], 0.0
    elif rules.natural:  # it pays more, and draws against any dealer 21
        win[_NATURAL], lose[_NATURAL] = 1.0 - made[:, -1], 0.0
    return lose, np.maximum(0.0, 1.0 - win - lose), win


# ---------------------------------------------------------------------------
# Policies and the optimum, on the model


def _observed(policy: np.ndarray) -> np.ndarray:
    """A policy array's entry at each model state's observation (a natural's is the soft 21's)."""
    pol = np.asarray(policy)
    if pol.shape != POLICY_SHAPE:
        raise ValueError(f"policy must have shape {POLICY_SHAPE}, got {pol.shape}")
    return pol[_OBSERVED]


@cache
def _hands(rules: BlackjackRules) -> FiniteMDP:
    """`blackjack_model` cut at `LONGEST_HAND` steps, which no hand outlasts: the same values,
    found by as many sweeps."""
    return blackjack_model(rules).replace(horizon=LONGEST_HAND)


def policy_value(policy: np.ndarray, rules: BlackjackRules = DEFAULT_RULES) -> float:
    """The exact expected return of a deterministic policy (`POLICY_SHAPE`, 0 stick, 1 hit,
    read at the decision states; ``(21, d, 1)``'s applies to a natural too)."""
    acts = _observed(policy)
    if not np.isin(acts, (STICK, HIT)).all():
        raise ValueError("policy entries at decision states must be 0 (stick) or 1 (hit)")
    return evaluate(_hands(rules), acts.astype(np.int64)).value


def mixed_policy_value(hit_probability: np.ndarray, rules: BlackjackRules = DEFAULT_RULES) -> float:
    """The exact expected return of a policy that hits with the given probability
    (`POLICY_SHAPE`, in [0, 1] at every decision state)."""
    p = np.asarray(_observed(hit_probability), dtype=np.float64)
    if not ((p >= 0.0) & (p <= 1.0)).all():
        raise ValueError("hit probabilities at decision states must be in [0, 1]")
    return evaluate(_hands(rules), np.column_stack([1.0 - p, p])).value


# The model states behind the observation (21, d, 1): the drawn soft 21s, then the naturals.
_ALIASED = np.r_[_SOFT_21 * DEALERS + np.arange(DEALERS), _NATURAL * DEALERS + np.arange(DEALERS)]


@cache
def _solve(rules: BlackjackRules) -> tuple[np.ndarray, np.ndarray]:
    """Q* (`[model states, 2]`) and the optimal hits (ties to a stick); at the one aliased
    observation, (21, d, 1), the action with the better start value per up card."""
    model = _hands(rules)
    values = []
    for action in (STICK, HIT):  # the model with both actions at the aliased states this one
        arrays = {name: getattr(model, name).copy()
                  for name in ("next_state", "prob", "reward", "terminal")}
        for array in arrays.values():
            array[_ALIASED] = array[_ALIASED, action][:, None]
        values.append(solve(model.replace(**arrays)).v)
    start = [(model.initial * v).reshape(_N_LIVE, DEALERS).sum(axis=0) for v in values]
    hit_at_21 = np.tile(start[HIT] > start[STICK] + _TIE_TOLERANCE, _N_LIVE)
    q = backup(model, np.where(hit_at_21, values[HIT], values[STICK]), 1.0)
    hit = q[:, HIT] > q[:, STICK] + _TIE_TOLERANCE
    hit[_ALIASED] = hit_at_21[_ALIASED]
    for array in (q, hit):
        array.setflags(write=False)
    return q, hit


def _occupancy(hit: np.ndarray) -> np.ndarray:
    """P(the hand passes through each live state | up card) under the hit mask, `[29, 10]`."""
    start = occupancy = np.repeat(_INITIAL[:, None], DEALERS, axis=1)
    mask = hit.reshape(_N_LIVE, DEALERS)
    for _ in range(_N_LIVE):  # a hand never comes back to a state: it meets fewer than 29
        occupancy = start + _HIT_MATRIX[:, :_N_LIVE].T @ (occupancy * mask)
    return occupancy


Soft21 = Literal["observation", "natural", "drawn"]


def optimal_action_values(
    rules: BlackjackRules = DEFAULT_RULES, *, soft_21: Soft21 = "observation"
) -> np.ndarray:
    """Q*(observation, action), ``[player_sum, dealer_card, usable_ace, action]`` (NaN off
    the decision states). ``(21, d, 1)`` is a natural or a drawn soft 21: ``soft_21`` picks
    one, or "observation" averages them by how often the optimal policy meets each."""
    q_model, hit = _solve(rules)
    drawn, natural = q_model[_ALIASED[:DEALERS]], q_model[_ALIASED[DEALERS:]]
    if soft_21 == "natural":
        at_21 = natural
    elif soft_21 == "drawn":
        at_21 = drawn
    elif soft_21 == "observation":
        occupancy = _occupancy(hit)
        w_nat, w_drawn = occupancy[_NATURAL][:, None], occupancy[_SOFT_21][:, None]
        at_21 = (w_nat * natural + w_drawn * drawn) / (w_nat + w_drawn)
    else:
        raise ValueError(f"soft_21 must be 'observation', 'natural' or 'drawn', not {soft_21!r}")
    q = np.full((*POLICY_SHAPE, 2), np.nan)
    q[tuple(o[:N_BASE] for o in _OBSERVED)] = q_model[:N_BASE]
    q[21, 1:, 1] = at_21
    return q


def optimal_policy(rules: BlackjackRules = DEFAULT_RULES) -> np.ndarray:
    """An optimal deterministic policy over observations, `POLICY_SHAPE` int8: hit (1) or
    stick (0, also for ties and states that need no decision)."""
    policy = np.zeros(POLICY_SHAPE, dtype=np.int8)
    policy[_OBSERVED] = _solve(rules)[1]
    return policy


def optimal_value(rules: BlackjackRules = DEFAULT_RULES) -> float:
    """The exact expected return of an optimal policy from the initial deal."""
    q, hit = _solve(rules)
    return float(_hands(rules).initial @ np.where(hit, q[:, HIT], q[:, STICK]))


def observation_rows() -> np.ndarray:
    """The row of the learners' table (the observation keyer's: mixed radix 32 x 11 x 2
    over (player_sum, dealer_card, usable_ace)) of each model state; a natural's is
    the soft 21's, which it shows as."""
    total, dealer, usable = _OBSERVED
    return (total * 11 + dealer) * 2 + usable


@cache
def blackjack_model(rules: BlackjackRules = DEFAULT_RULES) -> FiniteMDP:
    """The game under `rules` as a `FiniteMDP` (kept), for the engine and for planning sweep
    by sweep: a stick ends in a loss, a push or a win; a hit leads to a live state or a bust."""
    lose_pay, push_pay = rules.payoffs[:2]
    n_states, width = _N_LIVE * DEALERS, _N_LIVE + 1
    live = np.repeat(np.arange(_N_LIVE), DEALERS)
    next_state = np.broadcast_to(np.arange(n_states)[:, None, None], (n_states, 2, width)).copy()
    prob, reward = np.zeros((n_states, 2, width)), np.zeros((n_states, 2, width))
    terminal = np.zeros((n_states, 2, width), dtype=bool)
    paid = np.full(_N_LIVE, rules.payoffs[2])  # a stick that wins (a natural more, if paid so)
    if rules.natural and not rules.sab:
        paid[_NATURAL] = rules.payoffs[3]
    pays = (np.full(n_states, lose_pay), np.full(n_states, push_pay), paid[live])
    for k, (chance, pay) in enumerate(zip(stick_chances(rules), pays, strict=True)):
        prob[:, 0, k] = chance.reshape(-1)
        reward[:, 0, k] = pay
        terminal[:, 0, k] = True
    prob[:, 1] = _HIT_MATRIX[live]
    next_state[:, 1, :_N_LIVE] = np.arange(_N_LIVE) * DEALERS + (_OBSERVED[1] - 1)[:, None]
    reward[:, 1, :_N_LIVE] = push_pay
    reward[:, 1, _BUST], terminal[:, 1, _BUST] = lose_pay, True
    initial = (_INITIAL[:, None] * _CARD_PROBS[None, :]).reshape(-1)
    return FiniteMDP(next_state, prob, reward, terminal, initial, action_names=("stick", "hit"))
