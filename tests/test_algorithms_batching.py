"""The batched rule and the rule one transition at a time are the same rule.

For transitions that do not touch each other's rows (distinct states, next
states elsewhere), one batch of B equals B batches of one, for every
algorithm: exactly against non-sequential batches of one (the same closed
form), and up to rounding against the scalar engine's sequential form.
Duplicate (state, action) pairs in a batch are applied in batch order.
"""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import (
    ALGORITHMS,
    DoubleQLearning,
    Learner,
    MonteCarlo,
    Transitions,
    algorithm,
)

N_STATES, N_ACTIONS, B = 40, 3, 12
HP = {"learning_rate": 0.3, "discount": 0.9, "epsilon_start": 0.2, "epsilon_final": 0.2}
TD_NAMES = [cls.name for cls in ALGORITHMS if cls is not MonteCarlo]


class _FixedCoins(DoubleQLearning):
    """Double Q with its coins fixed, so that batching cannot change which table learns."""

    pattern: list[bool] = []

    def _coins(self, n: int) -> np.ndarray:
        out, self.pattern = self.pattern[:n], self.pattern[n:]
        return np.array(out, dtype=bool)


def _make(name: str, schedule: str, **extra) -> Learner:
    cls = _FixedCoins if name == "double-q" else algorithm(name)
    learner = cls(N_ACTIONS, {**HP, "learning_rate_schedule": schedule, **extra},
                  n_states=N_STATES, seed=0)
    rng = np.random.default_rng(9)  # distinct values: no ties, so tie-break draws do not matter
    for spec in learner.tables:
        if spec.name.startswith("q"):
            getattr(learner, spec.name)[:] = rng.normal(size=(N_STATES, N_ACTIONS))
    return learner


def _independent_batch(rng: np.random.Generator) -> Transitions:
    states = rng.permutation(N_STATES // 2)[:B]
    next_states = N_STATES // 2 + rng.integers(0, N_STATES // 2, B)  # never updated here
    return Transitions(
        states, rng.integers(0, N_ACTIONS, B), rng.normal(size=B), next_states,
        rng.random(B) < 0.3, rng.random(B) < 0.2, rng.integers(0, N_ACTIONS, B),
    )


def _row(batch: Transitions, i: int, sequential: bool) -> Transitions:
    return Transitions(
        batch.state[i:i + 1], batch.action[i:i + 1], batch.reward[i:i + 1],
        batch.next_state[i:i + 1], batch.terminated[i:i + 1], batch.truncated[i:i + 1],
        batch.next_action[i:i + 1], np.array([i]), sequential=sequential,
    )


def _tables(learner: Learner) -> dict[str, np.ndarray]:
    return {name: array for name, array in learner.state().arrays.items()}


@pytest.mark.parametrize("schedule", ["visits", "constant"])
@pytest.mark.parametrize("name", TD_NAMES)
def test_a_batch_equals_its_rows_one_at_a_time(name: str, schedule: str) -> None:
    extra = {"planning_steps": 0} if name == "dyna-q" else {}  # planning draws differ by batch
    batched = _make(name, schedule, **extra)
    closed = _make(name, schedule, **extra)
    textbook = _make(name, schedule, **extra)
    rng = np.random.default_rng(4)
    for _ in range(6):
        batch = _independent_batch(rng)
        coins = rng.random(B) < 0.5
        for learner in (batched, closed, textbook):
            learner.pattern = coins.tolist()  # only Double Q reads it
        td = batched.update(batch)
        td_rows = [closed.update(_row(batch, i, False))[0] for i in range(B)]
        td_seq = [textbook.update(_row(batch, i, True))[0] for i in range(B)]
        assert np.array_equal(td, td_rows)
        np.testing.assert_allclose(td, td_seq, rtol=1e-12, atol=1e-12)
    for key, array in _tables(batched).items():
        assert np.array_equal(array, _tables(closed)[key]), key
        np.testing.assert_allclose(array, _tables(textbook)[key], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", ["q-learning", "sarsa", "expected-sarsa", "dyna-q"])
def test_duplicate_pairs_apply_in_batch_order(name: str) -> None:
    extra = {"planning_steps": 0} if name == "dyna-q" else {}
    batched = _make(name, "visits", **extra)
    one_by_one = _make(name, "visits", **extra)
    # Five terminal transitions from one pair: fixed targets r, applied in order.
    rewards = np.array([1.0, -2.0, 0.5, 3.0, 0.0])
    n = len(rewards)
    batch = Transitions(np.full(n, 2), np.full(n, 1), rewards, np.full(n, 30),
                        np.ones(n, dtype=bool), np.zeros(n, dtype=bool), np.zeros(n, dtype=int))
    batched.update(batch)
    for i in range(n):
        one_by_one.update(_row(batch, i, True))
    assert batched.q[2, 1] == pytest.approx(one_by_one.q[2, 1], rel=1e-12)
    assert batched.counts[2, 1] == n == one_by_one.counts[2, 1]


@pytest.mark.parametrize("first_visit", [True, False])
@pytest.mark.parametrize("schedule", ["visits", "constant"])
def test_monte_carlo_episodes_side_by_side_equal_one_after_another(
    first_visit: bool, schedule: str
) -> None:
    hp = {**HP, "learning_rate_schedule": schedule, "first_visit": first_visit}
    together = MonteCarlo(N_ACTIONS, hp, n_states=N_STATES, seed=0)
    apart = MonteCarlo(N_ACTIONS, hp, n_states=N_STATES, seed=0)
    rng = np.random.default_rng(5)
    envs, steps = 4, 6
    # Each env walks its own 10 states (revisiting some), ending on the last step.
    states = np.array([e * 10 + rng.integers(0, 5, steps) for e in range(envs)])
    actions = rng.integers(0, N_ACTIONS, (envs, steps))
    rewards = rng.normal(size=(envs, steps))
    ends = np.zeros((envs, steps), dtype=bool)
    ends[:, -1] = True
    for t in range(steps):
        together.update(Transitions(states[:, t], actions[:, t], rewards[:, t],
                                    states[:, t] + 5, ends[:, t], np.zeros(envs, dtype=bool),
                                    env=np.arange(envs)))
    for e in range(envs):
        for t in range(steps):
            apart.update(Transitions.one(int(states[e, t]), int(actions[e, t]),
                                         float(rewards[e, t]), int(states[e, t]) + 5,
                                         bool(ends[e, t]), env=e))
    np.testing.assert_allclose(together.q, apart.q, rtol=1e-12, atol=1e-12)
    assert np.array_equal(together.counts, apart.counts)
    assert together.counts.sum() > 0


def test_monte_carlo_keeps_one_trajectory_per_env_and_forgets_on_request() -> None:
    learner = MonteCarlo(2, {"discount": 1.0, "learning_rate": 1e-6}, n_states=5, seed=0)
    learner.update(Transitions.one(0, 0, 1.0, 1, False, env=3))
    learner.update(Transitions.one(2, 1, 5.0, 3, False, env=0))  # another episode, env 0
    learner.forget_episodes([0])
    learner.update(Transitions.one(1, 1, 2.0, 4, True, env=3))
    # env 3's episode: G = 3 for (0,0), 2 for (1,1); env 0's step was dropped
    assert learner.q[0, 0] == 3.0 and learner.q[1, 1] == 2.0 and learner.q[2, 1] == 0.0


@pytest.mark.parametrize("name", [cls.name for cls in ALGORITHMS])
def test_an_empty_batch_changes_nothing(name: str) -> None:
    learner = _make(name, "visits")
    before = _tables(learner)
    empty = np.zeros(0, dtype=np.int64)
    td = learner.update(Transitions(empty, empty, np.zeros(0), empty, np.zeros(0, dtype=bool),
                                    np.zeros(0, dtype=bool), empty, empty))
    assert td.shape == (0,) and learner.last_update is None
    for key, array in _tables(learner).items():
        assert np.array_equal(array, before[key]), key
