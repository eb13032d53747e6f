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


def _backward_sums(x: np.ndarray, discount: float) -> tuple[np.ndarray, np.ndarray | None]:
    """The returns G_t = x_t + γ G_{t+1} along each row of `x` (k, T), G_T = 0, in
    two parts: `sums` (k, T), reversed in time (column u is t = T-1-u), and
    `weights` (T,) or None, such that G_t = sums[:, T-1-t] / weights[t] (or
    sums[:, T-1-t] itself). `x` may be overwritten.

    Computed without a loop over t: within blocks short enough that γ^t stays
    far from underflow, G_t = (Σ_{j>=t} γ^j x_j + γ^e G_e) / γ^t.
    """
    if discount == 0.0:
        return x[:, ::-1], None
    if discount == 1.0:
        return np.cumsum(x[:, ::-1], axis=1), None
    k, steps = x.shape
    block = max(1, int(200 / -np.log10(discount)))  # γ^block >= 1e-200
    if steps <= block:  # the usual case: one block, nothing carried in
        weights = discount ** np.arange(steps, dtype=np.float64)
        x *= weights
        return np.cumsum(x[:, ::-1], axis=1), weights
    out = np.empty((k, steps))
    carry = np.zeros(k)
    for start in range((steps - 1) // block * block, -1, -block):
        end = min(start + block, steps)
        weights = discount ** np.arange(end - start + 1, dtype=np.float64)
        partial = np.cumsum((x[:, start:end] * weights[:-1])[:, ::-1], axis=1)[:, ::-1]
        out[:, start:end] = (partial + weights[-1] * carry[:, None]) / weights[:-1]
        carry = out[:, start]
    return out[:, ::-1], None


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
    # Env e's episode so far is row e of `_cells` (flat (state, action) cells) and of
    # `_rewards`; `_next[e]` is the flat place of its next step in them, so its
    # length is `_next[e] - e * width`. `_longest` is at least the longest length.
    # Rows and columns grow by doubling.
    def forget_episodes(self, envs: Sequence[int] | np.ndarray | None = None) -> None:
        if envs is None:
            self._cells = np.zeros((0, 16), dtype=np.int64)
            self._rewards = np.zeros((0, 16), dtype=np.float64)
            self._next = np.zeros(0, dtype=np.int64)
            self._longest = 0
            return
        envs = np.asarray(envs, dtype=np.int64)
        envs = envs[envs < len(self._next)]
        self._next[envs] = envs * self._cells.shape[1]

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.forget_episodes()

    def _resize(self, rows: int, width: int) -> None:
        """Room for `rows` envs' episodes of up to `width` steps, keeping what is kept."""
        old_rows, old_width = self._cells.shape
        lengths = self._next - np.arange(old_rows) * old_width
        for name in ("_cells", "_rewards"):
            old = getattr(self, name)
            grown = np.zeros((rows, width), dtype=old.dtype)
            grown[:old_rows, :old_width] = old
            setattr(self, name, grown)
        self._next = np.arange(rows) * width
        self._next[:old_rows] += lengths

    def _record_steps(self, envs: np.ndarray, cells: np.ndarray, rewards: np.ndarray) -> None:
        """Append one step to each env's episode, making room first."""
        rows, width = self._cells.shape
        if self._longest >= width:  # perhaps no room for one more step: look closer
            self._longest = int((self._next - np.arange(rows) * width).max(initial=0))
            if self._longest >= width:
                self._resize(rows, max(2 * width, self._longest + 1))
        try:
            at = self._next[envs]
        except IndexError:  # a new env id
            self._resize(max(2 * rows, int(envs.max()) + 1), self._cells.shape[1])
            at = self._next[envs]
        self._cells.reshape(-1)[at] = cells
        self._rewards.reshape(-1)[at] = rewards
        self._next[envs] = at + 1
        self._longest += 1

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
        self._record_steps(envs, batch.state * self.n_actions + batch.action, batch.reward)
        errors = np.zeros(len(batch))
        ended = (batch.terminated | batch.truncated).nonzero()[0]
        single = len(batch) == 1
        if ended.size:
            tails = None
            if batch.truncated.any():
                cut = np.flatnonzero(~batch.terminated[ended])
                if cut.size:
                    tails = np.zeros(len(ended))
                    values = self.action_values(batch.next_state[ended[cut]])
                    tails[cut] = expected_values(values, self.epsilon)
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
        self, envs: np.ndarray, tails: np.ndarray | None, keep: bool, sequential: bool
    ) -> tuple[np.ndarray, tuple[Any, ...]]:
        """Move Q toward the returns of the episodes of `envs`, which just ended
        (`tails`: the value each ends on, None for all 0).

        The book's order is episode after episode, each from its last step back
        to its first; only the order among the updates of one cell changes the
        result, so first visits (one per episode and cell) go sorted by cell.
        """
        k = len(envs)
        width = self._cells.shape[1]
        starts = envs * width
        lengths = self._next[envs] - starts
        self._next[envs] = starts
        steps = int(lengths.max())
        valid = np.arange(steps) < lengths[:, None]
        x = np.where(valid, self._rewards[envs, :steps], 0.0)
        if tails is not None:
            x[np.arange(k), lengths - 1] += self.hp.discount * tails
        sums, weights = _backward_sums(x, self.hp.discount)
        cells = self._cells[envs, :steps]
        if self.hp.first_visit:
            # The entries, episode after episode and forward in time: their places in
            # `cells`, episodes and times (a 2-d nonzero is several times slower).
            places = valid.reshape(-1).nonzero()[0]
            owner = np.repeat(np.arange(k), lengths)
            times = places - owner * steps
            forward = cells.reshape(-1)[places]
            sortable = forward.astype(np.uint16) if self.q.size <= 1 << 16 else forward
            order = np.argsort(sortable, kind="stable")
            moved, owner = forward[order], owner[order]
            first = np.empty(len(order), dtype=bool)
            first[0] = True
            np.not_equal(moved[1:], moved[:-1], out=first[1:])
            first[1:] |= owner[1:] != owner[:-1]
            picked = first.nonzero()[0]
            moved, owner, times = moved[picked], owner[picked], times[order[picked]]
            if keep:  # the book's order, as the step-by-step view lists the updates
                book = np.lexsort((-times, owner))
                moved, owner, times = moved[book], owner[book], times[book]
            targets = sums[owner, steps - 1 - times]
            if weights is not None:
                targets /= weights[times]
        else:
            backward = valid[:, ::-1]
            moved = cells[:, ::-1][backward]
            targets = (sums if weights is None else sums / weights[::-1])[backward]
            owner = np.repeat(np.arange(k), lengths)
        before = self.q.reshape(-1)[moved] if keep else None
        td = self._move(self.q, self.counts, moved, targets, sequential)
        errors = np.bincount(owner, weights=np.abs(td), minlength=k)
        applied: tuple[Any, ...] = ()
        if keep:
            counts_after = self.counts.reshape(-1)[moved]
            applied = (moved, targets, before, counts_after, float(sums[0, steps - 1]),
                       0.0 if tails is None else float(tails[0]))
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
