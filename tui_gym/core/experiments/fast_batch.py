"""A `SeedBatch` of Q-learning or SARSA on a deterministic model, in few numpy calls per step.

A batch qualifies when its learner is exactly `QLearning` or `Sarsa`
(`fast_rule`) and its game a `ModelSteps` whose every move has one outcome.
`run_fast(batch, ...)` then plays it as `SeedBatch.run` does, with
the same draws from the same generators in the same order, so the tables,
returns and exact values come out bit for bit the same (a model with one
start state draws nothing for a start, which no number depends on); it only
does less work per step:

- the model's moves are read through tables over the batch's own cells (the
  next row, reward and termination of each seed's (state, action)), so one
  gather per quantity replaces the per-step state bookkeeping;
- the update is `move_toward` specialised to what a seed batch always has,
  one cell per row and every cell different (each seed owns its rows): each
  cell moves once, `Q <- keep * Q + α t`, with `α` and `keep` looked up by
  visit count from tables worked out by the same expressions as the closed form
  (made longer as counts grow, so a count indexes them as it is);
- each row's maximum is kept as rows change, the episode limit is looked at
  only when an episode may have reached it, and visit counts are added once
  at the end (a row's visits are its cells' counts);
- epsilon-greedy reads its numbers from blocks of the generator's raw output
  (`block_draws`), and skips the tie-break when no row has a tie (the numbers
  it would have used are passed over all the same);
- with epsilon constant, SARSA picks a new episode's first action as the
  episode starts rather than at the next step (nothing changes in between),
  except before a step that looks at the stop flag, so a stopped run has
  drawn exactly what the general loop drew;
- seeds that have played all their episodes leave the working arrays, so
  the seeds still playing are contiguous and never indexed through a mask.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.algorithms import Learner, QLearning, Sarsa
from tui_gym.algorithms.exploration import _COLUMN_LOOP
from tui_gym.algorithms.steps import _TINY
from tui_gym.core.experiments.block_draws import Draws, block_draws

if TYPE_CHECKING:
    from tui_gym.core.experiments.seed_batch import SeedBatch

__all__ = ["fast_rule", "run_fast", "step_size_tables"]

# Visit counts beyond this many distinct step sizes are left to the general update.
_MAX_STEP_SIZES = 1 << 16


def step_size_tables(learning_rate: float, schedule: str) -> tuple[np.ndarray, np.ndarray] | None:
    """`α` and `keep` by a cell's count before its update, the last entry for every larger count.

    The closed form of `move_toward` gives a cell updated once in a batch
    `keep * Q + α t`, with `keep = exp(log(max(1 - α, tiny)))`; these are the
    same expressions, elementwise, so the numbers are the same. None when the
    schedule would need more entries than `_MAX_STEP_SIZES`.
    """
    if schedule == "visits":
        if learning_rate <= 0.0:
            return None
        last = int(np.ceil(1.0 / learning_rate))
        while last > 0 and 1.0 / last <= learning_rate:  # the first count from which α is flat
            last -= 1
        while 1.0 / (last + 1) > learning_rate:
            last += 1
        if last >= _MAX_STEP_SIZES:
            return None
        counts = np.arange(last + 1, dtype=np.int64)
        alpha = np.maximum(learning_rate, 1.0 / (counts + np.ones(last + 1, dtype=np.int64)))
    else:
        alpha = np.full(1, learning_rate)
    keep = np.exp(np.log(np.maximum(1.0 - alpha, _TINY)))
    return alpha, keep


def fast_rule(learner: Learner) -> tuple[np.ndarray, np.ndarray] | None:
    """The step-size tables when `learner` can learn on the fast path, else None.

    The batch's game must also be a `ModelSteps` whose every move has one
    outcome (`SeedBatch` checks that).
    """
    if type(learner) not in (QLearning, Sarsa):
        return None
    hp = learner.hp
    return step_size_tables(float(hp.learning_rate), str(hp.learning_rate_schedule))


def _act(
    q: np.ndarray,
    best: np.ndarray,
    rows: np.ndarray,
    eps: np.ndarray | float,
    draws: Draws,
) -> np.ndarray:
    """`epsilon_greedy_batch(q[rows], eps, rng)`, the same draws in the same order;
    `best` holds each row's maximum."""
    k, n_actions = len(rows), q.shape[1]
    values = q.take(rows, axis=0)
    tied = values == best.take(rows).reshape(k, 1)
    ties = k * n_actions
    p = draws.p
    if p + ties + k > draws.size:
        draws.reserve(ties + k)
        p = draws.p
    dbl = draws.dbl
    draws.p = p + ties + k
    if _count_nonzero(tied) == k:  # one best action per row: the draws cannot change it
        actions = tied.argmax(axis=1)
    else:
        actions = np.where(tied, dbl[p:p + ties].reshape(k, n_actions), -1.0).argmax(axis=1)
    explore = (dbl[p + ties:p + ties + k] < eps).nonzero()[0]
    if explore.size:
        draws.integers_into(actions, explore)
    return actions


def _row_max(values: np.ndarray) -> np.ndarray:
    """`exploration.row_max`, the same maximum calls in the same order, with fewer copies."""
    if values.shape[1] > _COLUMN_LOOP:
        return values.max(axis=1)
    columns = values.T
    out = columns[0]
    for j in range(1, len(columns)):
        out = _maximum(out, columns[j])
    return out


def _row_max_any_order(values: np.ndarray) -> np.ndarray:
    """Each row's maximum, the columns taken in a quicker order for four (the same
    numbers, but a zero's sign may differ: only for comparing, never for arithmetic)."""
    if values.shape[1] != 4:
        return _row_max(values)
    c = values.T
    return _maximum(_maximum(c[0], c[1]), _maximum(c[2], c[3]))


_maximum = np.maximum
_count_nonzero = np.count_nonzero


def _grown(table: np.ndarray, length: int) -> np.ndarray:
    """`table` with its last entry repeated up to `length` entries."""
    return np.concatenate((table, np.full(length - len(table), table[-1])))


def run_fast(
    batch: SeedBatch,
    tables: tuple[np.ndarray, np.ndarray],
    *,
    stop: Callable[[], bool] | None,
    report: Callable[[SeedBatch], None] | None,
    interval: float,
    check_every: int,
) -> bool:
    """`SeedBatch.run` for a batch that qualifies (same arguments and result)."""
    draws = block_draws(batch.learner.rng, batch.steps.n_actions)
    try:
        return _run(batch, tables, draws, stop, report, interval, check_every)
    finally:
        draws.close()


def _run(
    batch: SeedBatch,
    tables: tuple[np.ndarray, np.ndarray],
    draws: Draws,
    stop: Callable[[], bool] | None,
    report: Callable[[SeedBatch], None] | None,
    interval: float,
    check_every: int,
) -> bool:
    steps: Any = batch.steps
    learner = batch.learner
    sarsa = learner.needs_next_action
    n_actions = steps.n_actions
    n_states = steps.n_states
    discount = float(learner.hp.discount)
    alpha_of, keep_of = tables
    constant_step = len(alpha_of) == 1
    alpha_0, keep_0 = float(alpha_of[0]), float(keep_of[0])
    q, counts, visits = learner.q, learner.counts, learner.visits
    q_flat, counts_flat = q.reshape(-1), counts.reshape(-1)
    episodes, returns, done = batch.episodes, batch.returns, batch.done
    horizon = steps.horizon
    constant_eps = batch._constant_epsilon
    forget = type(learner).forget_episodes is not Learner.forget_episodes
    # A count indexes the step-size tables directly: they are made longer than any count
    # can get before the next look (counts grow by at most one per batch step).
    highest_count = int(counts.max()) if counts.size else 0

    def cover(upto: int) -> None:
        nonlocal alpha_of, keep_of
        if not constant_step and len(alpha_of) <= upto:
            length = max(2 * len(alpha_of), upto + 1)
            alpha_of, keep_of = _grown(alpha_of, length), _grown(keep_of, length)

    cover(highest_count + check_every + 1)

    # The model's move from every cell of the batch's table: seed i's cell
    # (i * S + s) * A + a leads to row i * S + s'.
    seeds = batch.seeds
    cells_per_seed = n_states * n_actions
    shift = np.repeat(batch.offset, cells_per_seed)
    next_row_of = np.tile(steps._next[:, 0], seeds) + shift
    reward_of = np.tile(steps._reward[:, 0], seeds)
    terminal_of = np.tile(steps._terminal[:, 0], seeds)
    # Each row's maximum, kept up to date as rows change (the greedy choice and
    # Q-learning's target read it). Q-learning's moves that end an episode lead to an
    # extra row whose maximum stays 0, the target's future after termination.
    # SARSA only compares values with it: any order of the columns will do.
    row_max = _row_max_any_order if sarsa else _row_max
    best = row_max(q)
    if not sarsa:
        best = np.append(best, 0.0)
        next_row_of[terminal_of] = len(q)
    # A model with one start state: every episode starts there, whatever is drawn.
    starts = np.flatnonzero(steps.model.initial)
    only_start = int(starts[0]) if starts.size == 1 else None
    # Which episode counts are checkpoints (their tables are kept for exact valuing).
    checkpoint = np.zeros(episodes + 1, dtype=bool)
    checkpoint[batch.checkpoints] = batch.exact is not None

    # Episode counts after which something happens: a checkpoint, or the seed's last.
    event_of = checkpoint.copy()
    event_of[episodes] = True
    count_nonzero = np.count_nonzero

    start_rows = None if only_start is None else batch.offset + only_start

    def restart(envs: np.ndarray) -> np.ndarray:
        if start_rows is None:
            return batch.offset.take(envs) + steps.reset(envs)
        return start_rows.take(envs)

    # The seeds still playing, in seed order, and their per-seed working arrays.
    ids = np.flatnonzero(done < episodes)
    if not ids.size:
        batch._value_pending()
        if report is not None:
            report(batch)
        return True
    rows = restart(ids)
    # Episode limits: the batch step each episode began, and a bound below all of
    # them (it only grows), so the limit is looked at only when one may be reached.
    began = np.zeros(ids.size, dtype=np.int64)
    earliest = 0
    # Visits are counts summed over a row's actions: added once at the end.
    counts_before = counts.sum(axis=1)
    episode_return = np.zeros(ids.size)
    pending = np.full(ids.size, -1, dtype=np.int64)
    if forget:
        learner.forget_episodes(ids)
    last_report = time.monotonic()
    count = 0
    eps: np.ndarray | float = learner.epsilon if constant_eps is None else constant_eps
    # SARSA picks a new episode's first action as the episode starts (the same draws and
    # table as at the next step's start), except before a step that looks at the stop
    # flag: a run stopped there must not have drawn them. `fresh_due`: some are missing.
    early_first = sarsa and constant_eps is not None
    fresh_due = sarsa
    while ids.size:
        count += 1
        if count % check_every == 0:
            if stop is not None and stop():
                _leave_epsilon(learner, eps)
                visits += counts.sum(axis=1) - counts_before
                batch._value_pending()
                return False
            now = time.monotonic()
            if report is not None and now - last_report >= interval:
                report(batch)
                last_report = now
            cover(highest_count + count + check_every + 1)
        if constant_eps is None:
            eps = batch._epsilons(ids)
        if sarsa:
            actions = pending
            if fresh_due:
                fresh_due = not early_first
                fresh = (actions < 0).nonzero()[0]
                if fresh.size:
                    actions[fresh] = _act(
                        q, best, rows.take(fresh), eps if isinstance(eps, float) else eps[fresh],
                        draws,
                    )
        else:
            actions = _act(q, best, rows, eps, draws)
        cells = rows * n_actions + actions
        next_rows = next_row_of.take(cells)
        rewards = reward_of.take(cells)
        terminated = terminal_of.take(cells)
        if sarsa:
            pending = _act(q, best, next_rows, eps, draws)
            future = q_flat.take(next_rows * n_actions + pending)
            future[terminated] = 0.0
        else:
            future = best.take(next_rows)
        targets = rewards + future if discount == 1.0 else rewards + discount * future
        before = counts_flat.take(cells)
        if constant_step:
            q_flat[cells] = keep_0 * q_flat.take(cells) + alpha_0 * targets
        else:
            q_flat[cells] = keep_of.take(before) * q_flat.take(cells) + alpha_of.take(
                before) * targets
        counts_flat[cells] = before + 1
        best[rows] = row_max(q.take(rows, axis=0))
        rows = next_rows
        episode_return += rewards
        finished = terminated
        if horizon is not None and count - earliest >= horizon:
            earliest = int(began.min())
            if count - earliest >= horizon:
                finished = terminated | (count - began >= horizon)
        local = finished.nonzero()[0]
        if not local.size:
            continue
        ended = ids.take(local)
        number = done.take(ended)
        returns[ended, number] = episode_return.take(local)
        number += 1
        done[ended] = number
        episode_return[local] = 0.0
        if count_nonzero(event_of.take(number)):
            if count_nonzero(checkpoint.take(number)):
                batch._value_checkpoints(ended)
            if number.max() >= episodes:  # some seeds have played all their episodes
                more = number < episodes
                local, ended = local[more], ended[more]
                playing = done.take(ids) < episodes
                if local.size:
                    rows[local] = restart(ended)
                    began[local] = count
                    pending[local] = -1
                    fresh_due = sarsa
                    if forget:
                        learner.forget_episodes(ended)
                ids, rows, began = ids[playing], rows[playing], began[playing]
                episode_return, pending = episode_return[playing], pending[playing]
                continue
        starting = restart(ended) if start_rows is None else start_rows.take(ended)
        rows[local] = starting
        if horizon is not None:
            began[local] = count
        if forget:
            learner.forget_episodes(ended)
        if sarsa:
            if early_first and (count + 1) % check_every:
                pending[local] = _act(q, best, starting, eps, draws)
            else:
                pending[local] = -1
                fresh_due = True
    _leave_epsilon(learner, eps)
    visits += counts.sum(axis=1) - counts_before
    batch._value_pending()
    if report is not None:
        report(batch)
    return True


def _leave_epsilon(learner: Learner, eps: np.ndarray | float) -> None:
    """Set epsilon as the general loop leaves it: its last update's (the largest of a step's)."""
    learner.epsilon = eps if isinstance(eps, float) else float(eps.max())
