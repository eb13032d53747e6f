"""Blackjack's finite model over its observations, for the engine and every exact figure.

States 0..703 are the env's observations `(player_sum, dealer_card,
usable_ace)` numbered as the observation keyer numbers them (mixed radix
32 x 11 x 2); states 704..713 are the opening natural against each dealer
card, a state of its own (under `natural` or `sab` rules it pays otherwise
than a soft 21 drawn to) whose table row is the soft 21's (`ROWS`): the
agent cannot tell them apart. Hit draws a card of the infinite deck (a ten
with probability 4/13); a hand over 21 ends the episode with the loss's
reward and the raw total observed; stick ends it with the outcome of the
dealer's play (`solver`'s distribution of the dealer's final hand by up
card). Rewards are the rules' `payoffs`, so reward wrappers are followed;
the episode limit is a `TimeLimit`'s.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from tui_gym.core.mdp import FiniteMDP
from tui_gym.games.blackjack.solver import _CARD_PROBS, BlackjackRules, _dealer_final

__all__ = ["OBSERVATIONS", "blackjack_model", "observation_row"]

OBSERVATIONS = 32 * 11 * 2
_NATURALS = OBSERVATIONS  # the natural against dealer card d is state _NATURALS + d - 1
_CARDS = range(1, 11)
STICK, HIT = 0, 1


def observation_row(total: int, dealer: int, usable: int) -> int:
    """The keyer's row of the observation (player_sum, dealer_card, usable_ace)."""
    return (total * 11 + dealer) * 2 + usable


def _after_card(total: int, usable: bool, card: int) -> tuple[int, bool]:
    """The (sum, usable ace) after drawing `card`; a sum over 21 is a bust."""
    if usable:
        raw = total - 10 + card
        return (raw + 10, True) if raw <= 11 else (raw, False)
    if card == 1 and total + 11 <= 21:
        return total + 11, True
    return total + card, False


def _stick(total: int, dealer: int, natural: bool, rules: BlackjackRules) -> list[tuple]:
    """The outcomes (probability, reward) of sticking on `total` against up card `dealer`."""
    lose, push, win, paid = rules.payoffs
    final = _dealer_final()[dealer - 1]  # 17, 18, 19, 20, 21 drawn, natural, bust
    if natural and rules.sab:
        return [(final[5], push), (1.0 - final[5], win)]
    scores = (17, 18, 19, 20, 21, 21)
    p_win = final[6] + sum(p for p, s in zip(final[:6], scores, strict=True) if s < total)
    p_lose = sum(p for p, s in zip(final[:6], scores, strict=True) if s > total)
    if natural and rules.natural:  # a natural that wins pays 1.5
        return [(p_win, paid), (1.0 - p_win - p_lose, push), (p_lose, lose)]
    return [(p_win, win), (1.0 - p_win - p_lose, push), (p_lose, lose)]


@lru_cache(maxsize=8)
def blackjack_model(
    rules: BlackjackRules, horizon: int | None = None
) -> tuple[FiniteMDP, np.ndarray]:
    """The model (see the module docstring) and the table row of each of its states."""
    lose, push = rules.payoffs[0], rules.payoffs[1]
    n_states = OBSERVATIONS + 10
    rows = np.arange(n_states)
    table: list[list[list[tuple]]] = []
    for state in range(n_states):
        if state >= _NATURALS:
            dealer, total, usable, natural = state - _NATURALS + 1, 21, True, True
            rows[state] = observation_row(21, dealer, 1)
        else:
            rest, usable_bit = divmod(state, 2)
            total, dealer = divmod(rest, 11)
            usable, natural = bool(usable_bit), False
        deciding = 1 <= dealer <= 10 and (4 <= total <= 21 if not usable else 12 <= total <= 21)
        if not deciding:  # never acted in (a bust, or no such hand): ends at once
            table.append([[(1.0, state, 0.0, True)]] * 2)
            continue
        stick = [(p, state, r, True) for p, r in _stick(total, dealer, natural, rules) if p > 0]
        hit = []
        for card, p in zip(_CARDS, _CARD_PROBS, strict=True):
            after, soft = _after_card(total, usable, card)
            if after > 21:
                hit.append((p, observation_row(after, dealer, 0), lose, True))
            else:
                hit.append((p, observation_row(after, dealer, int(soft)), push, False))
        table.append([stick, hit])
    initial = np.zeros(n_states)
    for dealer, p_dealer in zip(_CARDS, _CARD_PROBS, strict=True):
        for first, p1 in zip(_CARDS, _CARD_PROBS, strict=True):
            for second, p2 in zip(_CARDS, _CARD_PROBS, strict=True):
                p = p_dealer * p1 * p2
                if {first, second} == {1, 10}:
                    initial[_NATURALS + dealer - 1] += p
                elif 1 in (first, second):
                    initial[observation_row(first + second + 10, dealer, 1)] += p
                else:
                    initial[observation_row(first + second, dealer, 0)] += p
    model = FiniteMDP.from_table(table, initial, horizon=horizon, action_names=("stick", "hit"))
    rows.setflags(write=False)
    return model, rows
