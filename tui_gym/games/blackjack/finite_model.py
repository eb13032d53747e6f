"""Blackjack as a `FiniteMDP`, for planning sweep by sweep (the Plan view, `tui-gym plan`)."""

from __future__ import annotations

from functools import cache

import numpy as np

from tui_gym.core.mdp import FiniteMDP
from tui_gym.games.blackjack.solver import (
    _BUST,
    _CARD_PROBS,
    _HIT_MATRIX,
    _INITIAL,
    _N_LIVE,
    _NATURAL,
    _STATE_OBS,
    DEFAULT_RULES,
    BlackjackRules,
    stick_chances,
    stick_paid,
)

__all__ = ["N_BASE", "blackjack_model", "natural_base_rows", "observation_rows"]

DEALERS = 10
N_BASE = (18 + 10) * DEALERS  # the game's base states: 4-21 hard and 12-21 soft, per dealer card


def _base_index(total: int, usable: int, dealer: int) -> int:
    """The base state (game order) of an observation; `dealer` 1-10."""
    if usable:
        return 180 + (total - 12) * DEALERS + dealer - 1
    return (total - 4) * DEALERS + dealer - 1


def natural_base_rows() -> np.ndarray:
    """`[10]`: the base state (a soft 21 against each dealer card) each natural plays as."""
    return np.array([_base_index(21, 1, d) for d in range(1, DEALERS + 1)], dtype=np.int64)


def observation_rows() -> np.ndarray:
    """The row of the learners' table (the observation keyer's: mixed radix 32 x 11 x 2
    over (player_sum, dealer_card, usable_ace)) of each model state; a natural's is
    the soft 21's, which it shows as."""
    totals = np.r_[np.repeat(np.arange(4, 22), DEALERS), np.repeat(np.arange(12, 22), DEALERS),
                   np.full(DEALERS, 21)]
    dealers = np.tile(np.arange(1, DEALERS + 1), 18 + 10 + 1)
    usable = np.r_[np.zeros(18 * DEALERS), np.ones(11 * DEALERS)].astype(np.int64)
    rows = (totals * 11 + dealers) * 2 + usable
    rows.setflags(write=False)
    return rows


def _model_index() -> np.ndarray:
    """`[29, 10]`: the model state of each of the solver's live states per dealer card."""
    index = np.empty((_N_LIVE, DEALERS), dtype=np.int64)
    for i, (total, usable) in enumerate(_STATE_OBS):
        for d in range(1, DEALERS + 1):
            index[i, d - 1] = (N_BASE + d - 1 if i == _NATURAL else _base_index(total, usable, d))
    return index


@cache
def blackjack_model(rules: BlackjackRules = DEFAULT_RULES) -> FiniteMDP:
    """The game's model under `rules` (kept per rules)."""
    lose_pay, push_pay = rules.payoffs[:2]
    index = _model_index()
    n_states = N_BASE + DEALERS
    width = _N_LIVE + 1  # a hit: any live state or a bust; a stick: three endings
    next_state = np.repeat(np.arange(n_states)[:, None, None], 2, axis=1)
    next_state = np.repeat(next_state, width, axis=2)
    prob = np.zeros((n_states, 2, width))
    reward = np.zeros((n_states, 2, width))
    terminal = np.zeros((n_states, 2, width), dtype=bool)
    lose, push, win = stick_chances(rules)
    paid = stick_paid(rules)
    rows = index.reshape(-1)  # live state major, dealer card minor
    live = np.repeat(np.arange(_N_LIVE), DEALERS)
    for k, (chance, pay) in enumerate(((lose, lose_pay), (push, push_pay), (win, None))):
        prob[rows, 0, k] = chance.reshape(-1)
        reward[rows, 0, k] = paid[live] if pay is None else pay
        terminal[rows, 0, k] = True
    for j in range(_N_LIVE):
        prob[rows, 1, j] = _HIT_MATRIX[live, j]
        next_state[rows, 1, j] = index[j][np.tile(np.arange(DEALERS), _N_LIVE)]
        reward[rows, 1, j] = push_pay
    prob[rows, 1, _N_LIVE] = _HIT_MATRIX[live, _BUST]
    reward[rows, 1, _N_LIVE] = lose_pay
    terminal[rows, 1, _N_LIVE] = True
    initial = np.zeros(n_states)
    initial[rows] = (_INITIAL[:, None] * _CARD_PROBS[None, :]).reshape(-1)
    return FiniteMDP(next_state, prob, reward, terminal, initial, action_names=("stick", "hit"))
