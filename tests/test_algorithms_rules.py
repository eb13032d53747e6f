"""One hand-computed update per algorithm, and the record the step-by-step view shows.

Every number below is worked out in the comments from the rule in Sutton &
Barto (2nd ed.): the learners must reproduce them exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import (
    DoubleQLearning,
    DynaQ,
    ExpectedSarsa,
    Learner,
    MonteCarlo,
    QLearning,
    Sarsa,
)

CONSTANT = {"learning_rate": 0.5, "learning_rate_schedule": "constant", "discount": 0.9}


def _one(learner: Learner, s: int, a: int, r: float, s2: int, terminated: bool = False,
         truncated: bool = False, a2: int | None = None) -> float:
    return learner.update_one(s, a, r, s2, terminated, truncated, a2)


def test_q_learning_bootstraps_from_the_best_next_action() -> None:
    learner = QLearning(2, CONSTANT, n_states=3, seed=0)
    learner.q[1] = [1.0, 3.0]
    # target = 1 + 0.9 * max(1, 3) = 3.7; Q(0,1) = 0 + 0.5 * (3.7 - 0) = 1.85
    td = _one(learner, 0, 1, 1.0, 1)
    assert td == pytest.approx(3.7)
    assert learner.q[0, 1] == pytest.approx(1.85)
    record = learner.last_update
    assert record is not None and record.formula == "r + γ·max Q(s',·)"
    assert record.terms == (("r", 1.0), ("γ", 0.9), ("max Q(s',·)", 3.0))
    assert (record.target, record.td_error, record.step_size) == (
        pytest.approx(3.7), pytest.approx(3.7), 0.5)
    assert (record.before, record.after) == (0.0, pytest.approx(1.85))
    # Terminated: target = r = 2; Q(0,1) = 1.85 + 0.5 * (2 - 1.85) = 1.925
    _one(learner, 0, 1, 2.0, 1, terminated=True)
    assert learner.q[0, 1] == pytest.approx(1.925)
    assert learner.last_update.formula == "r" and learner.last_update.terms == (("r", 2.0),)
    # Truncated still bootstraps: target = 0 + 0.9 * 3 = 2.7; Q(0,0) = 1.35
    _one(learner, 0, 0, 0.0, 1, truncated=True)
    assert learner.q[0, 0] == pytest.approx(1.35)
    assert learner.counts[0].tolist() == [1, 2] and learner.visits[0] == 3


def test_sarsa_bootstraps_from_the_next_action_taken() -> None:
    learner = Sarsa(2, CONSTANT, n_states=3, seed=0)
    learner.q[1] = [1.0, 3.0]
    # a' = 0 (not the best): target = 1 + 0.9 * Q(1, 0) = 1.9; Q(0,1) = 0.95
    td = _one(learner, 0, 1, 1.0, 1, a2=0)
    assert td == pytest.approx(1.9)
    assert learner.q[0, 1] == pytest.approx(0.95)
    record = learner.last_update
    assert record.formula == "r + γ·Q(s',a')" and record.next_action == 0
    assert record.terms == (("r", 1.0), ("γ", 0.9), ("Q(s',a')", 1.0))
    assert record.target_action == 0
    assert learner.next_first
    with pytest.raises(ValueError, match="next action"):
        _one(learner, 0, 1, 1.0, 1)


def test_expected_sarsa_takes_the_expectation_under_epsilon_greedy() -> None:
    hp = {**CONSTANT, "epsilon_start": 0.2, "epsilon_final": 0.2}
    learner = ExpectedSarsa(2, hp, n_states=3, seed=0)
    learner.q[1] = [1.0, 3.0]
    # π(·|1) = [0.2/2, 0.2/2 + 0.8] = [0.1, 0.9]; E = 0.1 * 1 + 0.9 * 3 = 2.8
    # target = 1 + 0.9 * 2.8 = 3.52; Q(0,1) = 1.76
    _one(learner, 0, 1, 1.0, 1)
    assert learner.q[0, 1] == pytest.approx(1.76)
    assert learner.last_update.terms[-2:] == (("ε", 0.2), ("Σ π(a|s')·Q(s',a)", pytest.approx(2.8)))


def test_expected_sarsa_splits_the_greedy_share_among_ties() -> None:
    hp = {**CONSTANT, "epsilon_start": 0.3, "epsilon_final": 0.3}
    learner = ExpectedSarsa(3, hp, n_states=3, seed=0)
    learner.q[2] = [2.0, 2.0, -1.0]
    # π = 0.1 each + 0.7 / 2 for the two tied: [0.45, 0.45, 0.1]
    # E = 0.45 * 2 + 0.45 * 2 + 0.1 * -1 = 1.7; target = 0 + 0.9 * 1.7 = 1.53; Q = 0.765
    _one(learner, 0, 2, 0.0, 2)
    assert learner.q[0, 2] == pytest.approx(0.765)


@pytest.mark.parametrize("seed", range(4))
def test_double_q_updates_one_table_evaluated_by_the_other(seed: int) -> None:
    learner = DoubleQLearning(2, CONSTANT, n_states=3, seed=seed)
    learner.q_a[1] = [1.0, 3.0]
    learner.q_b[1] = [5.0, 2.0]
    # The coin is the first draw of the learner's generator: below 0.5 updates A.
    picks_a = np.random.default_rng(seed).random(1)[0] < 0.5
    _one(learner, 0, 1, 1.0, 1)
    record = learner.last_update
    if picks_a:
        # a* = argmax Q_A(1,·) = 1; target = 1 + 0.9 * Q_B(1, 1) = 2.8; Q_A(0,1) = 1.4
        assert record.table == "A" and learner.q_a[0, 1] == pytest.approx(1.4)
        assert learner.q_b[0, 1] == 0.0 and learner.counts_a[0, 1] == 1
        assert record.formula == "r + γ·Q_B(s', a*), a* = argmax Q_A(s',·)"
        assert record.target_action == 1 and record.terms[-1] == ("Q_B(s',a*)", 2.0)
    else:
        # a* = argmax Q_B(1,·) = 0; target = 1 + 0.9 * Q_A(1, 0) = 1.9; Q_B(0,1) = 0.95
        assert record.table == "B" and learner.q_b[0, 1] == pytest.approx(0.95)
        assert learner.q_a[0, 1] == 0.0 and learner.counts_b[0, 1] == 1
        assert record.formula == "r + γ·Q_A(s', a*), a* = argmax Q_B(s',·)"
        assert record.target_action == 0 and record.terms[-1] == ("Q_A(s',a*)", 1.0)
    assert learner.update_counts()[0].tolist() == [0, 1]


def test_double_q_acts_on_the_sum_of_its_tables() -> None:
    learner = DoubleQLearning(2, {**CONSTANT, "epsilon_start": 0.0, "epsilon_final": 0.0},
                              n_states=2, seed=0)
    learner.q_a[1] = [1.0, 3.0]  # alone it would pick 1
    learner.q_b[1] = [5.0, 2.0]  # sum [6, 5]: picks 0
    assert learner.act(1) == 0 and learner.greedy_actions(1) == (0,)
    assert learner.values([1]).tolist() == [[3.0, 2.5]]  # shown as the mean


def test_seeds_that_split_the_coin_both_ways_exist() -> None:
    coins = {np.random.default_rng(seed).random(1)[0] < 0.5 for seed in range(4)}
    assert coins == {True, False}  # so the test above checks both branches


def _mc_episode(learner: MonteCarlo) -> None:
    # s=0 a=0 r=1 -> s=0 a=0 r=2 -> s=1 a=1 r=4, terminated
    _one(learner, 0, 0, 1.0, 0)
    _one(learner, 0, 0, 2.0, 1)
    _one(learner, 1, 1, 4.0, 2, terminated=True)


def test_monte_carlo_first_visit_uses_the_return_from_the_first_visit() -> None:
    # γ = 1: G_2 = 4, G_1 = 2 + 4 = 6, G_0 = 1 + 6 = 7; first visit of (0,0) is t = 0.
    # Visits schedule with a tiny floor: the first update of a pair has step 1.
    learner = MonteCarlo(2, {"discount": 1.0, "learning_rate": 1e-6}, n_states=3, seed=0)
    _one(learner, 0, 0, 1.0, 0)
    assert learner.q[0, 0] == 0.0 and learner.last_update.target is None  # waits
    _one(learner, 0, 0, 2.0, 1)
    errors = _one(learner, 1, 1, 4.0, 2, terminated=True)
    assert learner.q[0, 0] == 7.0 and learner.q[1, 1] == 4.0
    assert learner.counts[0, 0] == 1 and learner.counts[1, 1] == 1
    assert errors == 11.0  # |4 - 0| + |7 - 0|
    record = learner.last_update
    assert record.episode_return == 7.0 and record.target == 4.0 and record.after == 4.0
    assert [(u.state, u.action, u.target) for u in record.episode_updates] == [
        (1, 1, 4.0), (0, 0, 7.0)]


def test_monte_carlo_every_visit_averages_backwards() -> None:
    # Backwards: (1,1) <- 4; (0,0) <- G_1 = 6 (n=1); (0,0) <- G_0 = 7 (n=2): mean 6.5
    learner = MonteCarlo(2, {"discount": 1.0, "learning_rate": 1e-6, "first_visit": False},
                         n_states=3, seed=0)
    _mc_episode(learner)
    assert learner.q[0, 0] == pytest.approx(6.5) and learner.counts[0, 0] == 2
    updates = learner.last_update.episode_updates
    assert [(u.target, u.step_size, u.before, u.after) for u in updates] == [
        (4.0, 1.0, 0.0, 4.0), (6.0, 1.0, 0.0, 6.0), (7.0, 0.5, 6.0, 6.5)]


def test_monte_carlo_constant_step_applies_the_visits_in_the_books_order() -> None:
    # Step 0.5: (0,0) <- 0 + 0.5 * 6 = 3, then 3 + 0.5 * (7 - 3) = 5
    learner = MonteCarlo(2, {"discount": 1.0, "learning_rate": 0.5, "first_visit": False,
                             "learning_rate_schedule": "constant"}, n_states=3, seed=0)
    _mc_episode(learner)
    assert learner.q[0, 0] == pytest.approx(5.0) and learner.q[1, 1] == pytest.approx(2.0)


def test_monte_carlo_truncation_ends_on_the_expected_value_of_the_last_state() -> None:
    hp = {"discount": 0.5, "learning_rate": 1e-6, "epsilon_start": 0.2, "epsilon_final": 0.2}
    learner = MonteCarlo(2, hp, n_states=3, seed=0)
    learner.q[2] = [1.0, 3.0]
    # V(2) = 0.1 * 1 + 0.9 * 3 = 2.8; G = 1 + 0.5 * 2.8 = 2.4
    _one(learner, 0, 0, 1.0, 2, truncated=True)
    assert learner.q[0, 0] == pytest.approx(2.4)
    assert learner.last_update.terms[-1] == ("Σ π(a|s')·Q(s',a)", pytest.approx(2.8))


def test_dyna_q_plans_from_its_model_after_the_real_update() -> None:
    learner = DynaQ(2, {**CONSTANT, "planning_steps": 2}, n_states=3, seed=0)
    learner.q[1] = [0.0, 3.0]
    # Real: target 1 + 0.9 * 3 = 3.7, Q(0,1) = 1.85. The model has only (0,1) -> (1, 1.0),
    # so both planning updates redo it: 1.85 + 0.5 * 1.85 = 2.775, + 0.5 * 0.925 = 3.2375.
    _one(learner, 0, 1, 1.0, 1)
    assert learner.q[0, 1] == pytest.approx(3.2375)
    assert learner.counts[0, 1] == 1 and learner.visits[0] == 1  # experience, not simulation
    record = learner.last_update
    assert record.planning_updates == 2 and record.after == pytest.approx(1.85)
    assert learner.model_next[0, 1] == 1 and learner.model_reward[0, 1] == 1.0
    assert not learner.model_terminated[0, 1] and learner.model_next[0, 0] == -1


def test_dyna_q_model_keeps_the_last_outcome_of_a_pair() -> None:
    learner = DynaQ(2, {**CONSTANT, "planning_steps": 0}, n_states=4, seed=0)
    _one(learner, 0, 1, 1.0, 2)
    _one(learner, 0, 1, 5.0, 3, terminated=True)
    assert learner.model_next[0, 1] == 3 and learner.model_reward[0, 1] == 5.0
    assert learner.model_terminated[0, 1]
