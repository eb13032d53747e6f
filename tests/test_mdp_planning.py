"""Planning sweep by sweep: hand-computed sweeps on a 2x2 grid, improvement with shared ties,
and the planner's methods ending where the exact solvers say."""

from __future__ import annotations

import numpy as np
import pytest

from tests.mdp_support import random_model
from tui_gym.core.mdp import FiniteMDP, evaluate, optimal_actions, solve
from tui_gym.core.mdp.evaluation import PolicyArrays
from tui_gym.core.mdp.planning import Planner, uniform_policy, value_sweep

UP, DOWN, LEFT, RIGHT = 0, 1, 2, 3


def two_by_two() -> FiniteMDP:
    """Cells 0 1 / 2 3; cell 0 is terminal; every move costs 1; off the grid, stay."""
    steps = ((-1, 0), (1, 0), (0, -1), (0, 1))
    next_state = np.zeros((4, 4, 1), dtype=int)
    terminal = np.zeros((4, 4, 1), dtype=bool)
    reward = -np.ones((4, 4, 1))
    for s in range(4):
        r, c = divmod(s, 2)
        for a, (dr, dc) in enumerate(steps):
            if s == 0:
                next_state[s, a], terminal[s, a], reward[s, a] = 0, True, 0.0
                continue
            n = min(max(r + dr, 0), 1) * 2 + min(max(c + dc, 0), 1)
            next_state[s, a], terminal[s, a] = n, n == 0
    return FiniteMDP(next_state, np.ones((4, 4, 1)), reward, terminal,
                     np.array([0.0, 1 / 3, 1 / 3, 1 / 3]))


def test_one_synchronous_and_one_in_place_sweep_by_hand() -> None:
    model = two_by_two()
    v = np.zeros(4)
    # Synchronous: every state from the old zeros, so each pays its -1 and no more.
    planner = Planner(model, values=v)  # the random policy
    delta = planner.evaluation_sweep()
    assert planner.v.tolist() == [0.0, -1.0, -1.0, -1.0] and delta == 1.0
    assert v.tolist() == [0.0] * 4  # the values given are not touched
    # In place, in index order: cell 3 reads cells 1 and 2 already at -1:
    # v(3) = -1 + (v(1) + v(3) + v(2) + v(3)) / 4 = -1 + (-1 + 0 - 1 + 0) / 4 = -1.5.
    planner = Planner(model, values=v, in_place=True)
    delta = planner.evaluation_sweep()
    assert planner.v.tolist() == [0.0, -1.0, -1.0, -1.5] and delta == 1.5
    # A second synchronous sweep from [0, -1, -1, -1]: cell 1's moves reach 1 (up, right:
    # -1 each), 3 (down: -1) and the terminal 0: -1 + (-1 - 1 - 1 + 0) / 4 = -1.75.
    planner = Planner(model, values=[0.0, -1.0, -1.0, -1.0])
    delta = planner.evaluation_sweep()
    assert planner.v.tolist() == [0.0, -1.75, -1.75, -2.0] and delta == 1.0


def test_a_value_sweep_by_hand_and_the_actions_it_took() -> None:
    model = two_by_two()
    new, delta, best = value_sweep(model, np.array([0.0, -1.0, -2.0, -3.0]), 0.5)
    # Cell 1: left into the terminal pays -1 and ends (up or right: -1 - 0.5 = -1.5);
    # cell 3: up to cell 1, -1 - 0.5 = -1.5 (left: -1 - 1 = -2; staying: -2.5).
    assert new.tolist() == [0.0, -1.0, -1.0, -1.5] and delta == 1.5
    assert np.flatnonzero(best[1]).tolist() == [LEFT]
    assert np.flatnonzero(best[2]).tolist() == [UP]
    assert np.flatnonzero(best[3]).tolist() == [UP]
    assert best[0].all()  # the terminal cell: every action ties


def test_improvement_shares_ties_and_keeps_actions_still_among_the_best() -> None:
    model = two_by_two()
    v = solve(model).v
    step = Planner(model, values=v).improvement()  # from the random policy
    assert step.policy[3].tolist() == [0.5, 0.0, 0.5, 0.0]  # up and left tie
    assert step.changed.tolist() == [False, True, True, True]
    # Going up from cell 3 alone is still among the best: kept, nothing changes.
    up_only = step.policy.copy()
    up_only[3] = [1.0, 0.0, 0.0, 0.0]
    again = Planner(model, policy=up_only, values=v).improvement()
    assert again.stable and np.array_equal(again.policy, up_only)


@pytest.mark.parametrize("in_place", [False, True])
def test_policy_and_value_iteration_end_at_the_optimum(in_place: bool) -> None:
    model = random_model(np.random.default_rng(3), n_states=7, n_actions=3, end_chance=0.2)
    optimum = solve(model, 0.9)
    for method in ("policy-iteration", "value-iteration"):
        planner = Planner(model, gamma=0.9, theta=1e-12, in_place=in_place)
        assert planner.run(method) and planner.done(method)
        assert np.allclose(planner.v, optimum.v, atol=1e-9), method
        assert (planner.policy > 0).sum(axis=1).min() >= 1
        assert ((planner.policy > 0) <= optimal_actions(optimum.q, 1e-6)).all(), method


def test_evaluation_ends_at_the_exact_value_in_place_in_fewer_sweeps() -> None:
    model = two_by_two()
    exact = evaluate(model, uniform_policy(model)).v
    synchronous = Planner(model, theta=1e-10)
    in_place = Planner(model, theta=1e-10, in_place=True)
    assert synchronous.run("evaluate") and in_place.run("evaluate")
    assert np.allclose(synchronous.v, exact, atol=1e-8)
    assert np.allclose(in_place.v, exact, atol=1e-8)
    assert in_place.sweeps < synchronous.sweeps


def test_policy_iteration_counts_its_sweeps_and_improvements() -> None:
    planner = Planner(two_by_two(), theta=1e-10)
    assert planner.step("policy-iteration") == "evaluation sweep" and planner.sweeps == 1
    planner.run("policy-iteration")
    assert planner.stable and planner.iterations == 1  # one improvement, then stable
    assert planner.v.tolist() == [0.0, -1.0, -1.0, -2.0]
    assert planner.step("policy-iteration") == ""  # done


def test_a_policy_that_never_ends_stops_at_the_sweep_limit() -> None:
    model = two_by_two()
    bump = np.zeros((4, 4))
    bump[:, DOWN] = 1.0  # cells 2 and 3 bump into the edge for ever
    planner = Planner(model, theta=1e-6, policy=bump)
    assert not planner.run("evaluate", max_sweeps=50)
    assert planner.sweeps == 50 and planner.v[3] == -50.0
    assert planner.never_ending().tolist() == [False, True, True, True]


def test_settings_are_checked_and_start_over_what_converged() -> None:
    planner = Planner(two_by_two(), theta=1e-6)
    planner.run("evaluate")
    with pytest.raises(ValueError, match="gamma"):
        planner.set_gamma(0.0)
    with pytest.raises(ValueError, match="theta"):
        planner.set_theta(-1.0)
    planner.set_gamma(0.5)
    assert not planner.done("evaluate")
    with pytest.raises(ValueError, match="method"):
        planner.step("guess")


def test_the_dense_and_the_gathered_sweeps_agree() -> None:
    model = random_model(np.random.default_rng(5), n_states=9, n_actions=4, outcomes=3)
    policy = np.random.default_rng(6).dirichlet(np.ones(4), size=9)
    arrays = PolicyArrays.of(model, policy)
    assert arrays.dense is not None
    gathered = PolicyArrays(arrays.reward, arrays.weight, arrays.target)
    v = np.random.default_rng(7).normal(size=9)
    assert np.allclose(arrays.sweep(v, 0.9), gathered.sweep(v, 0.9))
    dense_v, gathered_v = v.copy(), v.copy()
    assert arrays.sweep_in_place(dense_v, 0.9) == pytest.approx(
        gathered.sweep_in_place(gathered_v, 0.9))
    assert np.allclose(dense_v, gathered_v)
