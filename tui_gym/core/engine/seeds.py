"""Independent learners played to a number of episodes each: what comparisons and sweeps run,
and the exact values of their greedy policies (`greedy_values`), many at once."""

from __future__ import annotations

import graphlib
from collections.abc import Callable, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from tui_gym.core.engine import loop, rules
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.mdp import FiniteMDP, evaluate
from tui_gym.core.mdp.evaluation import horizon_sum, transition_matrix

__all__ = ["MAX_CHECKPOINTS", "checkpoint_episodes", "greedy_values", "play_learner"]

MAX_CHECKPOINTS = 20  # exact valuations per learner over a run
CALL_STEPS = 1 << 18  # transitions per call of the loop, between looks at the stop flag


def play_learner(
    learner: Any,
    model: ModelArrays,
    episodes: int,
    checkpoints: Sequence[int] | np.ndarray = (),
    stop: Callable[[], bool] | None = None,
    returns: np.ndarray | None = None,
    progress: Callable[[int], None] | None = None,
    column: int = loop.RETURN,
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Play `learner` for `episodes` episodes on `model` (fewer once `stop()`): each
    episode's `column` of the loop's output (into `returns` as they come, when given;
    `progress` hears the count), and its action values at each checkpoint reached."""
    cursor = loop.Cursor()
    out = np.zeros((min(episodes, 65_536), loop.COLUMNS))
    log = rules.new_log()
    returns = np.empty(episodes) if returns is None else returns
    tables: list[np.ndarray] = []
    marks = sorted(int(c) for c in checkpoints if 0 < c <= episodes)
    done = 0
    while done < episodes:
        goal = next((m for m in marks if m > done), episodes)
        played, _ = loop.play(learner, model, cursor, goal - done, CALL_STEPS, out, log)
        returns[done : done + played] = out[:played, column]
        done += played
        if done in marks and played:
            tables.append(learner.action_values(slice(None)).copy())
        if progress is not None:
            progress(done)
        if stop is not None and stop():
            break
    return returns[:done], tables


def checkpoint_episodes(episodes: int, most: int = MAX_CHECKPOINTS) -> np.ndarray:
    """The episode counts (1-based, the last one `episodes`) at which greedy policies are valued."""
    count = max(1, min(episodes, most))
    points = np.rint(np.linspace(episodes / count, episodes, count)).astype(np.int64)
    # Rising already: drop repeats (np.unique would load numpy.ma on first use).
    return points[np.concatenate(([True], points[1:] != points[:-1]))]


def greedy_values(model: FiniteMDP, q: np.ndarray) -> np.ndarray:
    """The exact value (gamma 1) of the greedy policy of each table `q[m, S, A]`, ties split
    evenly: along its path where it can (one outcome a move, one start), else by matrix
    powers or backward steps over the episode limit, else one at a time."""
    q = np.asarray(q, dtype=np.float64)
    tied = q == q.max(axis=2, keepdims=True)
    ties = tied.sum(axis=2)
    if model.horizon is not None and model.max_outcomes == 1 and len(q):
        starts = np.flatnonzero(model.initial)
        if starts.size == 1:
            values, walked = _path_values(model, tied, ties, int(starts[0]), model.horizon)
            rest = np.flatnonzero(~walked)
            if rest.size:
                values[rest] = _valued(model, tied[rest], ties[rest])
            return values
    return _valued(model, tied, ties)


def _path_values(
    model: FiniteMDP, tied: np.ndarray, ties: np.ndarray, start: int, horizon: int
) -> tuple[np.ndarray, np.ndarray]:
    """The rewards along each greedy policy's path from `start` over at most `horizon`
    moves, all at once by doubling (an ending move leads to a sink), and which policies
    met no tie on the way (only their values are right)."""
    m, n = ties.shape
    size = n + 1  # the states and the sink, per policy
    greedy = tied.argmax(axis=2)
    states = np.arange(n)
    lead = np.full((m, size), n, dtype=np.int64)
    earn = np.zeros((m, size))
    split = np.zeros((m, size), dtype=bool)
    ends = model.terminal[states, greedy, 0]
    lead[:, :n] = np.where(ends, n, model.next_state[states, greedy, 0])
    earn[:, :n] = model.reward[states, greedy, 0]
    split[:, :n] = ties > 1
    # Flat indices: policy i's states are i * size to (i + 1) * size - 1.
    first = np.arange(m, dtype=np.int64) * size
    lead = (lead + first[:, np.newaxis]).ravel()
    earn, split = earn.ravel(), split.ravel()
    at = first + start
    values = np.zeros(m)
    met = np.zeros(m, dtype=bool)
    remaining = horizon
    while remaining:
        if remaining & 1:
            values += earn[at]
            met |= split[at]
            at = lead[at]
        remaining >>= 1
        if remaining:
            earn = earn + earn[lead]
            split = split | split[lead]
            lead = lead[lead]
    return values, ~met


def _valued(model: FiniteMDP, tied: np.ndarray, ties: np.ndarray) -> np.ndarray:
    """`greedy_values` by the policies' matrices (see there), from their ties."""
    policy = tied / ties[..., np.newaxis]
    if model.horizon is not None and model.n_states <= _DENSE_STATES:
        return _horizon_values_dense(model, policy, model.horizon)
    if model.horizon is None and not _acyclic(model):
        return np.array([evaluate(model, p).value for p in policy])
    v = np.zeros((len(policy), model.n_states))
    reward, cont, nxt = model.expected_reward, model.continue_prob, model.next_state
    moving = np.arange(len(policy))  # tables whose values still change
    # With no limit on a model no episode can loop in (Blackjack's hands), backward steps
    # from 0 reach every policy's exact values within the longest episode, and stop.
    for _ in range(model.n_states if model.horizon is None else model.horizon):
        now = v[moving]
        after = (policy[moving] * (reward + (cont * now[:, nxt]).sum(axis=3))).sum(axis=2)
        changed = (after != now).any(axis=1)
        v[moving] = after
        # A table whose values did not change has reached its fixed point: every further
        # backward step gives the same values again.
        moving = moving[changed]
        if not moving.size:
            break
    return v @ model.initial


@lru_cache(maxsize=16)
def _acyclic(model: FiniteMDP) -> bool:
    """Whether no possible move that goes on leads back to a state already passed."""
    moves = (model.prob > 0) & ~model.terminal
    after = {s: model.next_state[s][moves[s]].tolist() for s in range(model.n_states)}
    try:
        tuple(graphlib.TopologicalSorter(after).static_order())
    except graphlib.CycleError:
        return False
    return True


_DENSE_STATES = 256  # up to this many states, policies are valued by matrix powers


def _horizon_values_dense(model: FiniteMDP, policy: np.ndarray, horizon: int) -> np.ndarray:
    """Σ_{t<H} P^t r per policy, P its transition matrix over continuing outcomes."""
    n, pairs = model.n_states, model.n_states * model.n_actions
    step = transition_matrix(
        model.continue_prob.reshape(pairs, -1), model.next_state.reshape(pairs, -1), n
    ).reshape(-1, model.n_actions, n)
    matrix = np.einsum("msa,sat->mst", policy, step)  # [m, S, S]
    reward = (policy * model.expected_reward).sum(axis=2)  # [m, S]
    return horizon_sum(matrix, reward, horizon) @ model.initial
