"""Tiny deterministic grids in numpy, played by the engine's compiled loop (`train`)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from tui_gym.algorithms import Learner
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.engine.seeds import play_learner
from tui_gym.core.mdp import FiniteMDP

UP, RIGHT, DOWN, LEFT = 0, 1, 2, 3
_MOVES = ((-1, 0), (0, 1), (1, 0), (0, -1))


@dataclass(frozen=True)
class GridMDP:
    """A deterministic grid: -1 a step, `cliff` cells cost `cliff_reward` and send back to start."""

    rows: int
    cols: int
    start: int
    goal: int
    next_state: np.ndarray  # (S, 4)
    reward: np.ndarray  # (S, 4)
    max_steps: int

    @property
    def n_states(self) -> int:
        return self.rows * self.cols

    def shortest(self) -> np.ndarray:
        """Steps from each state to the goal (breadth-first over the moves)."""
        dist = np.full(self.n_states, -1)
        dist[self.goal] = 0
        queue = deque([self.goal])
        while queue:
            s = queue.popleft()
            for p in range(self.n_states):
                if dist[p] < 0 and p != self.goal and s in self.next_state[p]:
                    dist[p] = dist[s] + 1
                    queue.append(p)
        return dist


def grid(rows: int, cols: int, start: tuple[int, int], goal: tuple[int, int],
         cliff: tuple[tuple[int, int], ...] = (), cliff_reward: float = -100.0,
         max_steps: int = 100) -> GridMDP:
    n = rows * cols
    nxt = np.zeros((n, 4), dtype=np.int64)
    rew = np.full((n, 4), -1.0)
    start_s = start[0] * cols + start[1]
    for r in range(rows):
        for c in range(cols):
            for a, (dr, dc) in enumerate(_MOVES):
                rr, cc = min(max(r + dr, 0), rows - 1), min(max(c + dc, 0), cols - 1)
                if (rr, cc) in cliff:
                    nxt[r * cols + c, a] = start_s
                    rew[r * cols + c, a] = cliff_reward
                else:
                    nxt[r * cols + c, a] = rr * cols + cc
    return GridMDP(rows, cols, start_s, goal[0] * cols + goal[1], nxt, rew, max_steps)


def open_grid() -> GridMDP:
    """4x4, start bottom-left, goal top-right: every shortest path takes 6 steps."""
    return grid(4, 4, start=(3, 0), goal=(0, 3), max_steps=50)


def cliff_walk() -> GridMDP:
    """Sutton & Barto's Example 6.6: 4x12, the cliff along the bottom edge."""
    return grid(4, 12, start=(3, 0), goal=(3, 11),
                cliff=tuple((3, c) for c in range(1, 11)), max_steps=1000)


def as_model(mdp: GridMDP) -> FiniteMDP:
    """The grid as a finite model: every move certain, the goal ends the episode."""
    return FiniteMDP(
        next_state=mdp.next_state[..., None],
        prob=np.ones(mdp.next_state.shape + (1,)),
        reward=mdp.reward[..., None],
        terminal=(mdp.next_state == mdp.goal)[..., None],
        initial=np.eye(mdp.n_states)[mdp.start],
        horizon=mdp.max_steps,
    )


def train(learner: Learner, mdp: GridMDP, episodes: int) -> np.ndarray:
    """Play `episodes` episodes with the engine's loop; their returns."""
    returns, _ = play_learner(learner, ModelArrays.of(as_model(mdp)), episodes)
    return returns


def greedy_is_optimal(learner: Learner, mdp: GridMDP) -> bool:
    """Whether every action tied for the best value, in every state but the goal, is on a
    shortest path to the goal."""
    dist = mdp.shortest()
    values = learner.action_values(np.arange(mdp.n_states))
    for s in range(mdp.n_states):
        if s == mdp.goal:
            continue
        best = np.flatnonzero(values[s] == values[s].max())
        if any(dist[mdp.next_state[s, a]] != dist[s] - 1 for a in best):
            return False
    return True


def greedy_path_is_shortest(learner: Learner, mdp: GridMDP) -> bool:
    """Whether every greedy way from the start (any tie taken) reaches the goal by a
    shortest path."""
    dist = mdp.shortest()
    values = learner.action_values(np.arange(mdp.n_states))
    seen, frontier = {mdp.start}, [mdp.start]
    while frontier:
        s = frontier.pop()
        for a in np.flatnonzero(values[s] == values[s].max()):
            nxt = int(mdp.next_state[s, a])
            if dist[nxt] != dist[s] - 1:
                return False
            if nxt != mdp.goal and nxt not in seen:
                seen.add(nxt)
                frontier.append(nxt)
    return True
