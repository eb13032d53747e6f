"""Step sizes, and moving table entries toward targets a whole batch at once.

Two learning-rate schedules are shared by every learner: `constant` (always
the learning rate) and `visits` (`max(learning_rate, 1/n)` for the n-th update
of a (state, action): a plain average of targets until 1/n reaches the rate).

`move_toward` applies a batch of targets to a table. Targets are formed by
the learner from the table as it is before the batch. Transitions that share
a (state, action) are applied one after the other in batch order, each with
its own step size, exactly as one-at-a-time updates would apply them if the
targets stayed fixed; this is done in closed form: after updates 1..m with step
sizes a_i, Q = prod(1 - a_i) Q_0 + sum_i a_i prod_{j>i}(1 - a_j) t_i, the
products taken as sums of logs within each group of a sorted batch. A
`sequential` batch of one (a one-at-a-time stream, the scalar engine) is the
textbook `Q <- Q + a (t - Q)`; the two forms agree up to rounding.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LEARNING_RATE_SCHEDULES", "move_toward", "step_size"]

LEARNING_RATE_SCHEDULES = ("constant", "visits")

# 1 - lr is floored here before taking logs: a step size of 1 wipes out what came before.
_TINY = 1e-300


def step_size(learning_rate: float, schedule: str, n: int) -> float:
    """The step size of the n-th update (n >= 1) of one (state, action)."""
    if schedule == "visits":
        return max(learning_rate, 1.0 / n)
    return learning_rate


def move_toward(
    q: np.ndarray,
    counts: np.ndarray,
    visits: np.ndarray,
    cells: np.ndarray,
    targets: np.ndarray,
    learning_rate: float,
    schedule: str,
    *,
    count: bool = True,
    sequential: bool = False,
) -> np.ndarray:
    """Move `q` at flat `cells` (row * n_actions + action) toward `targets`; return the TD errors.

    `q` and `counts` are C-contiguous (rows, n_actions) arrays, `visits` has one
    entry per row. With `count` each update adds one to `counts` of its cell
    and to `visits` of its row, and the "visits" schedule counts it; without
    (simulated updates), counts stay and every update of a cell takes the step
    size of its current count. The TD errors are `targets - Q` before the batch.
    `sequential` applies a batch of one as `Q + a (t - Q)`, not in closed form.
    """
    n_actions = q.shape[1]
    q_flat = q.reshape(-1)
    counts_flat = counts.reshape(-1)
    td = targets - q_flat[cells]
    m = len(cells)
    if m == 0:
        return td
    if m == 1 and sequential:
        cell = int(cells[0])
        if count:
            counts_flat[cell] += 1
            visits[cell // n_actions] += 1
        step = learning_rate
        if schedule == "visits":
            step = max(step, 1.0 / max(counts_flat[cell], 1))
        q_flat[cell] += step * td[0]
        return td

    # A stable sort of small integers is a radix sort in numpy: several times faster.
    sortable = cells.astype(np.uint16) if q_flat.size <= 1 << 16 else cells
    order = np.argsort(sortable, kind="stable")
    sorted_cells = cells[order]
    goals = targets[order]
    first = np.empty(m, dtype=bool)
    first[0] = True
    np.not_equal(sorted_cells[1:], sorted_cells[:-1], out=first[1:])
    starts = first.nonzero()[0]
    ends = np.empty_like(starts)
    ends[:-1] = starts[1:] - 1
    ends[-1] = m - 1
    sizes = ends - starts + 1
    group = np.repeat(np.arange(len(starts)), sizes)
    if schedule == "visits":
        if count:
            rank = np.arange(1, m + 1) - starts[group]
            alpha = np.maximum(learning_rate, 1.0 / (counts_flat[sorted_cells] + rank))
        else:
            alpha = np.maximum(learning_rate, 1.0 / np.maximum(counts_flat[sorted_cells], 1))
    else:
        alpha = np.full(m, learning_rate)
    log_keep = np.log(np.maximum(1.0 - alpha, _TINY))
    running = np.cumsum(log_keep)
    weights = alpha * np.exp(running[ends][group] - running)
    keep_all = np.exp(running[ends] - running[starts] + log_keep[starts])
    unique = sorted_cells[starts]
    q_flat[unique] = keep_all * q_flat[unique] + np.add.reduceat(weights * goals, starts)
    if count:
        counts_flat[unique] += sizes
        np.add.at(visits, unique // n_actions, sizes)
    return td
