"""Blackjack, many tables at once: Gymnasium's `Blackjack-v1` rules on numpy arrays.

`BatchedBlackjack` keeps `num_envs` hands in arrays and plays any subset of
them in one call. The rules are the env's own (see
gymnasium/envs/toy_text/blackjack.py), rewritten for batches:

- an infinite deck: a card is `min(rng.integers(1, 14), 10)`, the same
  distribution as Gymnasium's `np_random.choice(deck)` over its 13 faces;
- at reset the dealer gets two cards (one shown) and the player two;
- an ace counts 11 while that does not bust the hand ("usable ace");
- hit: one more card, and a hand over 21 ends the episode with -1;
- stick: the dealer draws while below 17 (a soft 17 stands) and the hands
  are compared (+1 / 0 / -1, a bust dealer scores 0);
- `natural=True`: a winning two-card 21 pays 1.5; `sab=True` (which overrides
  `natural`): a two-card 21 beats every dealer hand but a dealer natural, and
  two naturals draw.

Observations are rows `(player_sum, dealer_card, usable_ace)`, the flat form
of the env's `Tuple(Discrete(32), Discrete(11), Discrete(2))`; after a bust
the player sum is the raw total (up to 31), as in the env. The random stream
is not Gymnasium's (cards are drawn in a different order), so runs match the
scalar env in distribution, not draw for draw.
"""

from __future__ import annotations

import numpy as np

from tui_gym.core.vector.base import (
    BatchStep,
    Selection,
    after_step,
    check_actions,
    check_num_envs,
    selection_size,
)
from tui_gym.games.blackjack.solver import DEFAULT_RULES, BlackjackRules

__all__ = ["BatchedBlackjack"]

STICK, HIT = 0, 1
DEALER_STANDS = 17


def _best_total(raw: np.ndarray, has_ace: np.ndarray) -> np.ndarray:
    """A hand's total with one ace counted 11 when that does not bust it."""
    return raw + 10 * (has_ace & (raw <= 11))


class BatchedBlackjack:
    """`num_envs` independent games of `Blackjack-v1`, stepped together.

    State, one entry per env (public, so tests can set positions):
    `player_raw` (the player's total with aces as 1), `player_ace` (holds an
    ace), `natural` (the player's hand is still the opening ace + ten),
    `dealer_up` and `dealer_hole` (the dealer's two cards, aces as 1), and
    `elapsed` (steps taken this episode, for `max_episode_steps`).

    Args:
        num_envs: how many games.
        rules: the `natural` / `sab` reward variant.
        seed: seeds the card stream; the same seed deals the same cards.
        max_episode_steps: truncate episodes after this many steps (a
            `TimeLimit`); None for none (an episode lasts at most 20 steps).
    """

    n_actions = 2
    obs_width = 3

    def __init__(
        self,
        num_envs: int,
        rules: BlackjackRules = DEFAULT_RULES,
        seed: int | np.random.SeedSequence | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        self.num_envs = check_num_envs(num_envs)
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be >= 1, got {max_episode_steps}")
        self.rules = rules
        self.max_episode_steps = max_episode_steps
        self.rng = np.random.default_rng(seed)
        n = self.num_envs
        self.player_raw = np.zeros(n, dtype=np.int64)
        self.player_ace = np.zeros(n, dtype=bool)
        self.natural = np.zeros(n, dtype=bool)
        self.dealer_up = np.ones(n, dtype=np.int64)
        self.dealer_hole = np.ones(n, dtype=np.int64)
        self.elapsed = np.zeros(n, dtype=np.int64)

    def _cards(self, count: int | tuple[int, int]) -> np.ndarray:
        return np.minimum(self.rng.integers(1, 14, size=count), 10)

    # --- observing -------------------------------------------------------
    def _observe(self, raw: np.ndarray, ace: np.ndarray, up: np.ndarray) -> np.ndarray:
        usable = ace & (raw <= 11)
        obs = np.empty((len(raw), 3), dtype=np.int64)
        obs[:, 0] = raw + 10 * usable
        obs[:, 1] = up
        obs[:, 2] = usable
        return obs

    def observations(self, index: Selection = None) -> np.ndarray:
        """The current observation of each selected env: (k, 3) int64 rows."""
        sel = slice(None) if index is None else index
        return self._observe(self.player_raw[sel], self.player_ace[sel], self.dealer_up[sel])

    # --- acting ----------------------------------------------------------
    def reset(self, index: Selection = None) -> np.ndarray:
        """Deal new hands to the selected envs (all by default); returns their observations."""
        sel = slice(None) if index is None else index
        k = selection_size(index, self.num_envs)
        cards = self._cards((k, 4))  # dealer up, dealer hole, player, player
        player = cards[:, 2] + cards[:, 3]
        ace = (cards[:, 2] == 1) | (cards[:, 3] == 1)
        self.dealer_up[sel] = cards[:, 0]
        self.dealer_hole[sel] = cards[:, 1]
        self.player_raw[sel] = player
        self.player_ace[sel] = ace
        self.natural[sel] = ace & (player == 11)  # an ace and a ten
        self.elapsed[sel] = 0
        return self._observe(player, ace, cards[:, 0])

    def step(
        self, actions: np.ndarray, index: Selection = None, *, autoreset: bool = True
    ) -> BatchStep:
        """Apply one action (0 stick, 1 hit) to each selected env.

        With `autoreset`, envs whose episode ends are dealt a new hand at once:
        `BatchStep.next_obs` still shows how the episode ended and
        `BatchStep.obs` the new start. Without it they keep their final state
        until `reset` is called for them.
        """
        sel = slice(None) if index is None else index
        k = selection_size(index, self.num_envs)
        acts = check_actions(actions, k, self.n_actions)
        raw = np.array(self.player_raw[sel])
        ace = np.array(self.player_ace[sel])
        natural = np.array(self.natural[sel])
        up = self.dealer_up[sel]
        reward = np.zeros(k, dtype=np.float64)
        terminated = np.zeros(k, dtype=bool)

        hits = np.flatnonzero(acts == HIT)
        if hits.size:
            cards = self._cards(hits.size)
            raw[hits] += cards
            ace[hits] |= cards == 1
            natural[hits] = False  # three cards are never a natural
            bust = hits[raw[hits] > 21]
            terminated[bust] = True
            reward[bust] = -1.0
        sticks = np.flatnonzero(acts == STICK)
        if sticks.size:
            terminated[sticks] = True
            hole = self.dealer_hole[sel]
            reward[sticks] = self._settle(
                _best_total(raw[sticks], ace[sticks]), natural[sticks], up[sticks], hole[sticks]
            )

        self.player_raw[sel] = raw
        self.player_ace[sel] = ace
        self.natural[sel] = natural
        elapsed = self.elapsed[sel] + 1
        self.elapsed[sel] = elapsed
        next_obs = self._observe(raw, ace, up)
        truncated, obs = after_step(next_obs, terminated, elapsed, self.max_episode_steps,
                                    index, self.reset, autoreset)
        return BatchStep(next_obs, reward, terminated, truncated, obs)

    def _settle(
        self,
        player_total: np.ndarray,
        player_natural: np.ndarray,
        up: np.ndarray,
        hole: np.ndarray,
    ) -> np.ndarray:
        """Rewards of sticking: the dealer plays out every hand, then the hands compare."""
        raw = up + hole
        ace = (up == 1) | (hole == 1)
        dealer_natural = ace & (raw == 11)
        total = _best_total(raw, ace)
        drawing = np.flatnonzero(total < DEALER_STANDS)
        while drawing.size:
            cards = self._cards(drawing.size)
            raw[drawing] += cards
            ace[drawing] |= cards == 1
            new_total = _best_total(raw[drawing], ace[drawing])
            total[drawing] = new_total
            drawing = drawing[new_total < DEALER_STANDS]
        dealer_score = np.where(total > 21, 0, total)
        reward = np.sign(player_total - dealer_score).astype(np.float64)
        if self.rules.sab:
            reward[player_natural & ~dealer_natural] = 1.0
        elif self.rules.natural:
            reward[player_natural & (reward == 1.0)] = 1.5
        return reward
