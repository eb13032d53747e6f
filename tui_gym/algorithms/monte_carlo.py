"""Monte Carlo control with an epsilon-soft policy (Sutton & Barto, 2nd ed., section 5.4).

Nothing is learned during an episode: each env's states, actions and rewards
are kept, and when its episode ends the returns are computed backwards,

    G_T = 0 (termination)  or  Σ_a π(a|s_T) Q(s_T, a) (truncation),
    G_t = r_{t+1} + γ G_{t+1},

and every (s_t, a_t) moves toward its G_t, in the order t = T-1, ..., 0 as in
the book's loop: only at its first visit in the episode (`first_visit`) or at
every visit. With the "visits" schedule the step is 1/n (the incremental
average of the returns seen) until it reaches the learning rate; "constant"
is a constant step. A truncated episode ends on the expected value of its
last state under the current epsilon-greedy policy, since the time limit is
not part of the game. The policy is epsilon-greedy on Q (epsilon-soft), so
Q estimates the values of the exploring policy, as on-policy control does.

Episodes end per env: rows of a batch carry their env id
(`Transitions.env`), and all envs whose episodes end in one batch are
updated together. Unfinished episodes are not saved.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from tui_gym.algorithms.base import CellUpdate, Learner, Transitions, UpdateRecord
from tui_gym.algorithms.exploration import expected_values
from tui_gym.algorithms.settings import COMMON_PARAMS
from tui_gym.algorithms.steps import step_size
from tui_gym.core.params import Param

__all__ = ["MonteCarlo"]


def discounted_returns(
    rewards: np.ndarray, lengths: np.ndarray, tails: np.ndarray, discount: float
) -> np.ndarray:
    """G_t = r_t + γ G_{t+1} for each row of `rewards` (k, T), row i of length
    `lengths[i]` ending on the value `tails[i]`; entries past a row's end are 0.

    Computed without a loop over t: within blocks short enough that γ^t stays
    far from underflow, G_t = (Σ_{j>=t} γ^j r_j + γ^e G_e) / γ^t.
    """
    k, steps = rewards.shape
    r = np.where(np.arange(steps) < lengths[:, None], rewards, 0.0)
    last = np.flatnonzero(lengths > 0)
    r[last, lengths[last] - 1] += discount * tails[last]
    if discount == 0.0:
        return r
    if discount == 1.0:
        return np.cumsum(r[:, ::-1], axis=1)[:, ::-1]
    block = max(1, int(200 / -np.log10(discount)))  # γ^block >= 1e-200
    out = np.empty((k, steps))
    carry = np.zeros(k)
    for start in range((steps - 1) // block * block, -1, -block):
        end = min(start + block, steps)
        weights = discount ** np.arange(end - start + 1, dtype=np.float64)
        partial = np.cumsum((r[:, start:end] * weights[:-1])[:, ::-1], axis=1)[:, ::-1]
        out[:, start:end] = (partial + weights[-1] * carry[:, None]) / weights[:-1]
        carry = out[:, start]
    return out


class MonteCarlo(Learner):
    """On-policy Monte Carlo control; learns from whole episodes."""

    name = "monte-carlo"
    title = "Monte Carlo control"
    summary = "no bootstrapping: learns from whole-episode returns, at each episode's end"
    formula = "G = r + γ·G'"
    params = (
        *COMMON_PARAMS,
        Param("first_visit", bool, True,
              help="update a state-action once per episode, from its first visit",
              title="First visit"),
    )

    # --- episodes in progress -------------------------------------------------------
    def forget_episodes(self, envs: Sequence[int] | np.ndarray | None = None) -> None:
        if envs is None:
            self._states = np.zeros((0, 16), dtype=np.int64)
            self._actions = np.zeros((0, 16), dtype=np.int64)
            self._rewards = np.zeros((0, 16), dtype=np.float64)
            self._length = np.zeros(0, dtype=np.int64)
            return
        envs = np.asarray(envs, dtype=np.int64)
        self._length[envs[envs < len(self._length)]] = 0

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.forget_episodes()

    def _make_room(self, envs: np.ndarray) -> None:
        """Room for one more step of each env's episode."""
        width = int(envs.max()) + 1
        if width > len(self._length):
            grow = max(width, 2 * len(self._length)) - len(self._length)
            self._length = np.concatenate([self._length, np.zeros(grow, dtype=np.int64)])
            for name in ("_states", "_actions", "_rewards"):
                old = getattr(self, name)
                pad = np.zeros((grow, old.shape[1]), dtype=old.dtype)
                setattr(self, name, np.concatenate([old, pad]))
        longest = int(self._length[envs].max()) + 1
        if longest > self._states.shape[1]:
            extra = max(longest, 2 * self._states.shape[1]) - self._states.shape[1]
            for name in ("_states", "_actions", "_rewards"):
                old = getattr(self, name)
                pad = np.zeros((old.shape[0], extra), dtype=old.dtype)
                setattr(self, name, np.concatenate([old, pad], axis=1))

    # --- the rule ---------------------------------------------------------------------
    def update(self, batch: Transitions) -> np.ndarray:
        """Record the steps; at episodes' ends, learn from their returns.

        A row that ends an episode carries the sum of |G - Q(s, a)| over the
        episode's updates (so an engine's per-episode mean |TD| is their mean
        per step); other rows carry 0.
        """
        if not len(batch):
            self._last = None
            return np.zeros(0)
        envs = batch.envs()
        self._make_room(envs)
        t = self._length[envs]
        self._states[envs, t] = batch.state
        self._actions[envs, t] = batch.action
        self._rewards[envs, t] = batch.reward
        self._length[envs] = t + 1
        errors = np.zeros(len(batch))
        ended = np.flatnonzero(batch.terminated | batch.truncated)
        single = len(batch) == 1
        if ended.size:
            cut = ended[~batch.terminated[ended]]
            tails = np.zeros(len(ended))
            if cut.size:
                values = self.action_values(batch.next_state[cut])
                tails[~batch.terminated[ended]] = expected_values(values, self.epsilon)
            errors[ended], applied = self._learn(envs[ended], tails, single, batch.sequential)
        if single:
            cell = int(batch.state[0]) * self.n_actions + int(batch.action[0])
            now = self.q.reshape(-1)[cell]
            if ended.size:
                self._keep(batch, *applied, now)
            else:
                self._keep(batch, None, now)
        else:
            self._last = None
        return errors

    def _learn(
        self, envs: np.ndarray, tails: np.ndarray, keep: bool, sequential: bool
    ) -> tuple[np.ndarray, tuple[Any, ...]]:
        """Move Q toward the returns of the episodes of `envs`, which just ended."""
        hp = self.hp
        k = len(envs)
        lengths = self._length[envs]
        steps = int(lengths.max())
        states = self._states[envs, :steps]
        actions = self._actions[envs, :steps]
        rewards = self._rewards[envs, :steps]
        valid = np.arange(steps) < lengths[:, None]
        returns = discounted_returns(rewards, lengths, tails, hp.discount)
        cells = states * self.n_actions + actions
        chosen = valid
        if hp.first_visit:
            n_cells = len(self.visits) * self.n_actions
            flat = (np.arange(k)[:, None] * n_cells + cells)[valid]  # by env, then time
            _, first = np.unique(flat, return_index=True)
            is_first = np.zeros(len(flat), dtype=bool)
            is_first[first] = True
            chosen = np.zeros_like(valid)
            chosen[valid] = is_first
        # The book's order: each episode from its last step back to its first.
        backwards = chosen[:, ::-1]
        order_cells = cells[:, ::-1][backwards]
        order_returns = returns[:, ::-1][backwards]
        owner = np.broadcast_to(np.arange(k)[:, None], (k, steps))[:, ::-1][backwards]
        before = self.q.reshape(-1)[order_cells] if keep else None
        td = self._move(self.q, self.counts, order_cells, order_returns, sequential)
        self._length[envs] = 0
        errors = np.bincount(owner, weights=np.abs(td), minlength=k)
        applied: tuple[Any, ...] = ()
        if keep:
            counts_after = self.counts.reshape(-1)[order_cells]
            applied = (order_cells, order_returns, before, counts_after, float(returns[0, 0]),
                       float(tails[0]))
        return errors, applied

    # --- the record ----------------------------------------------------------------------
    def _describe(self, batch: Transitions, *numbers: Any) -> UpdateRecord:
        r = float(batch.reward[0])
        if numbers[0] is None:  # the episode goes on: nothing learned yet
            now = float(numbers[1])
            return self._record(batch, "G, at the episode's end", (("r", r),), None, now, now)
        cells, returns, before, counts_after, first_return, tail, now = numbers
        updates = self._replay(cells, returns, before, counts_after)
        state, action = int(batch.state[0]), int(batch.action[0])
        # This transition's own update: the first one of its (state, action) in the
        # book's backward order (its only one with first visits).
        own = next(u for u in updates if (u.state, u.action) == (state, action))
        terms: tuple[tuple[str, float], ...] = (("r", r),)
        formula = "G = r"
        if not batch.terminated[0]:
            formula = "G = r + γ·Σ π(a|s')·Q(s',a)"
            terms = (("r", r), ("γ", self.hp.discount), ("Σ π(a|s')·Q(s',a)", float(tail)))
        return self._record(
            batch, formula, terms, own.target, own.before, float(now), alpha=own.step_size,
            episode_return=first_return, episode_updates=tuple(updates),
        )

    def _replay(
        self, cells: np.ndarray, returns: np.ndarray, before: np.ndarray, counts_after: np.ndarray
    ) -> list[CellUpdate]:
        """The episode's updates one by one, as the batched form applied them."""
        hp = self.hp
        seen: dict[int, int] = {}
        total = {int(c): int(n) for c, n in zip(cells, counts_after, strict=True)}
        for c in cells:
            seen[int(c)] = seen.get(int(c), 0) + 1
        current = {int(c): float(b) for c, b in zip(cells, before, strict=True)}
        rank: dict[int, int] = {}
        out = []
        for c, g in zip(cells.tolist(), returns.tolist(), strict=True):
            rank[c] = rank.get(c, 0) + 1
            n = total[c] - seen[c] + rank[c]
            alpha = step_size(hp.learning_rate, hp.learning_rate_schedule, n)
            old = current[c]
            current[c] = old + alpha * (g - old)
            out.append(CellUpdate(c // self.n_actions, c % self.n_actions, g, alpha, old,
                                  current[c]))
        return out
