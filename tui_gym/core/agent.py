"""Tabular Q-learning: the quick-start tutorial's agent, made general and fast.

`Hyperparameters` gathers every knob in one validated dataclass; `QAgent`
holds the Q-table and does epsilon-greedy action selection (ties broken at
random with a seeded generator) and the one-step Q-learning update

    Q(s, a) <- Q(s, a) + lr * (r + discount * (1 - terminated) * max_a' Q(s', a') - Q(s, a))

The table is one numpy array: dense observation spaces index it directly,
other spaces map each new key to the next free row. `values(keys)` reads many
states at once for heatmaps and exact evaluation.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from tui_gym.core.params import Param


@dataclass(frozen=True)
class Hyperparameters:
    """Everything that shapes a Q-learning run.

    The defaults suit a game of short episodes with noisy +-1 outcomes (each
    game states its own: see the README): an undiscounted return (the game's
    value is undiscounted, and an episode lasts a few steps), and a step size
    that starts as a plain average of what each (state, action) has seen (1/n)
    and settles at `learning_rate`, so
    the noisy +-1 outcomes average out quickly and then keep tracking the
    improving estimates of the next state.
    """

    learning_rate: float = 0.001  # step size per update, in (0, 1]; the floor under "visits"
    discount: float = 1.0  # gamma, per step
    epsilon_start: float = 1.0  # exploration rate at episode 0
    epsilon_final: float = 0.05  # exploration rate once the decay is over
    epsilon_decay_fraction: float = 0.5  # share of the episode budget spent decaying, linearly
    episodes: int = 200_000  # the training budget, in episodes
    # "constant" (the tutorial's) or "visits": max(learning_rate, 1/n(s, a))
    learning_rate_schedule: str = "visits"

    def __post_init__(self) -> None:
        for rng in HYPERPARAMETER_FIELDS:
            object.__setattr__(self, rng.name, rng.parse(getattr(self, rng.name)))
        if self.learning_rate_schedule not in LEARNING_RATE_SCHEDULES:
            raise ValueError(
                f"learning_rate_schedule must be one of {', '.join(LEARNING_RATE_SCHEDULES)}, "
                f"got {self.learning_rate_schedule!r}"
            )
        if self.epsilon_final > self.epsilon_start:
            raise ValueError(
                f"epsilon_final ({self.epsilon_final:g}) must not exceed "
                f"epsilon_start ({self.epsilon_start:g})"
            )

    def epsilon_at(self, episode: int) -> float:
        """The exploration rate for a 0-based episode number."""
        decay_episodes = self.epsilon_decay_fraction * self.episodes
        if decay_episodes <= 0 or episode >= decay_episodes:
            return self.epsilon_final
        frac = episode / decay_episodes
        return self.epsilon_start + frac * (self.epsilon_final - self.epsilon_start)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Hyperparameters:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"unknown hyperparameter(s): {', '.join(unknown)}")
        return cls(**dict(data))

    def replace(self, **changes: Any) -> Hyperparameters:
        return Hyperparameters.from_dict({**self.to_dict(), **changes})


LEARNING_RATE_SCHEDULES = ("constant", "visits")

_DEFAULTS: dict[str, Any] = {f.name: f.default for f in fields(Hyperparameters)}
HYPERPARAMETER_FIELDS: tuple[Param, ...] = tuple(
    Param(name, kind, _DEFAULTS[name], low, high, help_text, title=title, min_inclusive=closed)
    for name, title, kind, low, high, closed, help_text in (
        ("learning_rate", "Learning rate", float, 0.0, 1.0, False, "step size of each update"),
        ("discount", "Discount", float, 0.0, 1.0, True, "weight of the next state's value"),
        ("epsilon_start", "Epsilon start", float, 0.0, 1.0, True, "exploration at the start"),
        ("epsilon_final", "Epsilon final", float, 0.0, 1.0, True, "exploration after decay"),
        ("epsilon_decay_fraction", "Decay fraction", float, 0.0, 1.0, True,
         "share of the budget spent decaying epsilon"),
        ("episodes", "Episodes", int, 1, 1_000_000_000, True, "training budget"),
    )
)
FIELD_BY_NAME: dict[str, Param] = {f.name: f for f in HYPERPARAMETER_FIELDS}


class QAgent:
    """An epsilon-greedy tabular Q-learning agent over `n_actions` actions.

    `n_states` fixes a dense table (keys are row numbers); `None` grows the
    table as new keys are seen.
    """

    def __init__(
        self,
        n_actions: int,
        hyperparameters: Hyperparameters | None = None,
        *,
        n_states: int | None = None,
        seed: int | None = None,
    ) -> None:
        if n_actions < 1:
            raise ValueError(f"n_actions must be >= 1, got {n_actions}")
        self.n_actions = int(n_actions)
        self.hp = hyperparameters or Hyperparameters()
        self.n_states = n_states
        self.rng = np.random.default_rng(seed)
        self.episode = 0  # episodes finished; drives the epsilon schedule
        self.epsilon = self.hp.epsilon_at(0)
        self._index: dict[Hashable, int] | None = None if n_states is not None else {}
        rows = n_states if n_states is not None else 256
        self.q = np.zeros((rows, self.n_actions), dtype=np.float64)
        self.visits = np.zeros(rows, dtype=np.int64)  # updates per state
        self.counts = np.zeros((rows, self.n_actions), dtype=np.int64)  # per (state, action)
        self._rows_used = rows if n_states is not None else 0

    # --- the table -------------------------------------------------------
    @property
    def dense(self) -> bool:
        return self._index is None

    def _row(self, key: Hashable) -> int:
        """The table row of a key, adding one for a new sparse key."""
        index = self._index
        if index is None:
            return key  # type: ignore[return-value]
        row = index.get(key)
        if row is None:
            row = self._rows_used
            if row == len(self.q):
                self.q = np.concatenate([self.q, np.zeros_like(self.q)])
                self.visits = np.concatenate([self.visits, np.zeros_like(self.visits)])
                self.counts = np.concatenate([self.counts, np.zeros_like(self.counts)])
            index[key] = row
            self._rows_used += 1
        return row

    def seen(self, key: Hashable) -> bool:
        """Whether the agent has updated this state at least once."""
        row = self._find(key)
        return row is not None and bool(self.visits[row])

    def _find(self, key: Hashable) -> int | None:
        """The table row of a key, or None when it was never seen."""
        if self._index is None:
            return key  # type: ignore[return-value]
        return self._index.get(key)

    @property
    def states_seen(self) -> int:
        """How many states have been updated at least once."""
        if self._index is None:
            return int(np.count_nonzero(self.visits))
        return self._rows_used

    def values(self, keys: Iterable[Hashable]) -> np.ndarray:
        """Q-values for many states at once: shape (len(keys), n_actions); unseen rows are 0."""
        keys = list(keys)
        out = np.zeros((len(keys), self.n_actions), dtype=np.float64)
        if self._index is None:
            if keys:
                out[:] = self.q[np.asarray(keys, dtype=np.int64)]
            return out
        for i, key in enumerate(keys):
            row = self._index.get(key)
            if row is not None:
                out[i] = self.q[row]
        return out

    def table(self) -> tuple[np.ndarray, list[Hashable] | None]:
        """A copy of the used part of the table and, for sparse tables, the key of each row."""
        if self._index is None:
            return self.q.copy(), None
        keys: list[Hashable] = [None] * self._rows_used
        for key, row in self._index.items():
            keys[row] = key
        return self.q[: self._rows_used].copy(), keys

    def update_counts(self) -> np.ndarray:
        """A copy of the per-(state, action) update counts, rows as in `table()`."""
        rows = len(self.q) if self._index is None else self._rows_used
        return self.counts[:rows].copy()

    def load_table(
        self, q: np.ndarray, keys: list[Hashable] | None, counts: np.ndarray | None = None
    ) -> None:
        """Replace the table (the inverse of `table()` and `update_counts()`)."""
        q = np.asarray(q, dtype=np.float64)
        if counts is None:
            # Unknown history: treat every learned value as well established.
            counts = np.where(q != 0, 1_000_000, 0)
        counts = np.asarray(counts, dtype=np.int64)
        if counts.shape != q.shape:
            raise ValueError(f"update counts have shape {counts.shape}, Q-table {q.shape}")
        if q.ndim != 2 or q.shape[1] != self.n_actions:
            raise ValueError(f"Q-table must have shape (states, {self.n_actions}), got {q.shape}")
        if keys is None:
            if self.n_states is None or q.shape[0] != self.n_states:
                raise ValueError("a dense Q-table must have one row per state")
            self.q = q.copy()
            self.counts = counts.copy()
            self.visits = counts.sum(axis=1)
            return
        if self.n_states is not None:
            raise ValueError("this agent has a dense table; the saved one is sparse")
        if len(keys) != len(q):
            raise ValueError("sparse Q-table keys and rows differ in number")
        self._index = {key: i for i, key in enumerate(keys)}
        self.q = np.zeros((max(256, len(q)), self.n_actions))
        self.q[: len(q)] = q
        self.counts = np.zeros(self.q.shape, dtype=np.int64)
        self.counts[: len(q)] = counts
        self.visits = self.counts.sum(axis=1)
        self._rows_used = len(q)

    # --- acting ----------------------------------------------------------
    def greedy(self, key: Hashable) -> int:
        """The best-valued action in a state, ties broken at random."""
        row = self._find(key)
        if row is None:
            return int(self.rng.integers(self.n_actions))
        return self._argmax(self.q[row])

    def greedy_actions(self, key: Hashable) -> tuple[int, ...]:
        """Every action that ties for the best value in a state."""
        row = self._find(key)
        if row is None:
            return tuple(range(self.n_actions))
        values = self.q[row]
        return tuple(int(a) for a in np.flatnonzero(values == values.max()))

    def _argmax(self, values: np.ndarray) -> int:
        best = values.max()
        ties = np.flatnonzero(values == best)
        if len(ties) == 1:
            return int(ties[0])
        return int(ties[self.rng.integers(len(ties))])

    def act(self, key: Hashable) -> int:
        """Epsilon-greedy: a random action with probability epsilon, else greedy."""
        if self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.n_actions))
        return self.greedy(key)

    # --- learning --------------------------------------------------------
    def update(
        self,
        key: Hashable,
        action: int,
        reward: float,
        terminated: bool,
        next_key: Hashable,
    ) -> float:
        """One Q-learning update; returns the TD error."""
        row = self._row(key)
        future = 0.0
        if not terminated:
            next_row = self._find(next_key)
            if next_row is not None:
                future = float(self.q[next_row].max())
        q_row = self.q[row]
        td = reward + self.hp.discount * future - q_row[action]
        counts = self.counts[row]
        counts[action] += 1
        lr = self.hp.learning_rate
        if self.hp.learning_rate_schedule == "visits":
            lr = max(lr, 1.0 / counts[action])
        q_row[action] += lr * td
        self.visits[row] += 1
        return float(td)

    def end_episode(self) -> None:
        """Count a finished episode and move epsilon along its schedule."""
        self.episode += 1
        self.epsilon = self.hp.epsilon_at(self.episode)

    def assign_from(self, other: QAgent) -> None:
        """Become a copy of `other` (table, counts, schedule, generator), keeping identity."""
        if other is self:
            return
        if other.n_actions != self.n_actions or other.n_states != self.n_states:
            raise ValueError("cannot take over an agent of a different shape")
        vars(self).update(vars(other))

    def set_hyperparameters(self, hp: Hyperparameters) -> None:
        """New knobs for the rest of the run; the table and episode count stay."""
        self.hp = hp
        self.epsilon = hp.epsilon_at(self.episode)
