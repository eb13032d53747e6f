"""Hand-computed updates of the chapter 7, 8 and 12 control learners, and what the step
panel says of them.

Every number is worked out in the comments from the rule in Sutton & Barto (2nd ed.),
with α = 0.5 (constant) and γ = 0.9: the learners must reproduce them exactly.
"""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import (
    DynaQPlus,
    NStepSarsa,
    PrioritizedSweeping,
    SarsaLambda,
    WatkinsQLambda,
)
from tui_gym.ui.widgets.step_panel import explain

CONSTANT = {"learning_rate": 0.5, "learning_rate_schedule": "constant", "discount": 0.9}


class _Event:
    episode, step, observation, next_observation = 1, 1, 0, 1


def _panel(record, names=("left", "right")) -> str:
    lines = explain(_Event(), record, names, lambda obs: f"obs {obs}",
                    describe_row=lambda row: f"row {row}")
    return "\n".join(f"{label} {text}" for label, text in lines)


def test_n_step_sarsa_waits_n_rewards_then_updates_the_pair_n_steps_back() -> None:
    learner = NStepSarsa(2, {**CONSTANT, "n": 2}, n_states=4, seed=0)
    learner.q[2] = [2.0, 4.0]
    # Step 0: one reward in the window, nothing updated.
    assert learner.update_one(0, 0, 1.0, 1, False, next_action=1) == 0.0
    record = learner.last_update
    assert record.target is None and not learner.q.any(axis=1)[:2].any()
    assert record.notes[0] == ("window", "r = +1  (1 of n = 2)")
    # Step 1: G = 1 + 0.9·2 + 0.81·Q(2,0) = 1 + 1.8 + 1.62 = 4.42 for (0,0); Q = 2.21.
    assert learner.update_one(1, 1, 2.0, 2, False, next_action=0) == pytest.approx(4.42)
    assert learner.q[0, 0] == pytest.approx(2.21) and learner.q[1, 1] == 0.0
    (pair,) = learner.last_update.episode_updates
    assert (pair.state, pair.action, pair.target) == (0, 0, pytest.approx(4.42))
    assert "row 0, left: G = +4.42  Q 0 → +2.21" in _panel(learner.last_update)
    # Step 2 ends: (1,1) gets G = 2 + 0.9·3 = 4.7 (Q 2.35), then (2,0) G = 3 (Q 2 → 2.5).
    learner.update_one(2, 0, 3.0, 3, True)
    assert learner.q[1, 1] == pytest.approx(2.35) and learner.q[2, 0] == pytest.approx(2.5)
    record = learner.last_update
    assert [(u.state, u.target) for u in record.episode_updates] == [
        (1, pytest.approx(4.7)), (2, pytest.approx(3.0))]
    assert (record.formula, record.target, record.before, record.after) == (
        "G = r", 3.0, 2.0, 2.5)
    # A new episode starts with an empty window.
    learner.update_one(3, 1, 5.0, 0, False, next_action=0)
    assert learner.last_update.notes[0] == ("window", "r = +5  (1 of n = 2)")


def test_n_step_sarsa_with_n_1_is_sarsa_and_a_truncation_bootstraps() -> None:
    learner = NStepSarsa(2, {**CONSTANT, "n": 1}, n_states=3, seed=0)
    learner.q[1] = [1.0, 3.0]
    # target = 1 + 0.9·Q(1,0) = 1.9; Q(0,1) = 0.95, as SARSA
    learner.update_one(0, 1, 1.0, 1, False, next_action=0)
    assert learner.q[0, 1] == pytest.approx(0.95)
    assert learner.last_update.formula == "G = r + γ·Q(s',a')"
    long = NStepSarsa(2, {**CONSTANT, "n": 3}, n_states=3, seed=0)
    long.q[1] = [1.0, 3.0]
    long.update_one(0, 0, 1.0, 2, False, next_action=0)
    # Truncated after two steps: (0,0) G = 1 + 0.9·(0 + 0.9·Q(1,1)) = 1 + 2.43 = 3.43;
    # (2,1) G = 0 + 0.9·3 = 2.7.
    long.update_one(2, 1, 0.0, 1, False, truncated=True, next_action=1)
    assert long.q[0, 0] == pytest.approx(1.715) and long.q[2, 1] == pytest.approx(1.35)


@pytest.mark.parametrize("cls", [SarsaLambda, WatkinsQLambda])
def test_a_td_error_spreads_over_the_traces_and_they_end_with_the_episode(cls) -> None:
    hp = {**CONSTANT, "lambda": 0.5, "traces": "accumulating"}
    learner = cls(2, hp, n_states=4, seed=0)
    learner.q[2] = [2.0, 0.0]
    # δ = 1 + 0.9·Q(1,·) - 0 = 1 (Q(1,·) = 0, a' greedy by a tie); Q(0,0) = 0.5;
    # then e(0,0) = γλ = 0.45.
    learner.update_one(0, 0, 1.0, 1, False, next_action=1)
    assert learner.q[0, 0] == pytest.approx(0.5)
    assert learner.eligibility()[0, 0] == pytest.approx(0.45)
    # δ = 0 + 0.9·2 - 0 = 1.8 (a' = 0 is greedy in state 2); Q(0,0) += 0.5·1.8·0.45 = 0.405
    # (0.905), Q(1,1) = 0.9; traces 0.2025 and 0.45.
    learner.update_one(1, 1, 0.0, 2, False, next_action=0)
    assert learner.q[0, 0] == pytest.approx(0.905) and learner.q[1, 1] == pytest.approx(0.9)
    assert learner.eligibility()[[0, 1], [0, 1]] == pytest.approx([0.2025, 0.45])
    record = learner.last_update
    assert [(u.state, u.trace) for u in record.episode_updates] == [
        (0, pytest.approx(0.45)), (1, 1.0)]
    assert "row 0, left: e = +0.45  Q +0.5 → +0.905" in _panel(record)
    assert "then every e × γλ = 0.45" in _panel(record)
    # Terminal: δ = 1 - Q(2,0) = -1; Q(0,0) -= 0.5·0.2025 (0.80375), Q(1,1) -= 0.225
    # (0.675), Q(2,0) = 1.5; every trace ends.
    learner.update_one(2, 0, 1.0, 3, True)
    assert learner.q[[0, 1, 2], [0, 1, 0]] == pytest.approx([0.80375, 0.675, 1.5])
    assert not learner.eligibility().any()


def test_replacing_traces_set_a_revisited_pair_to_one() -> None:
    hp = {**CONSTANT, "lambda": 1.0, "discount": 1.0}
    for kind, expected in (("replacing", 1.0), ("accumulating", 2.0)):
        learner = SarsaLambda(2, {**hp, "traces": kind}, n_states=2, seed=0)
        learner.update_one(0, 0, 0.0, 1, False, next_action=0)
        learner.update_one(1, 0, 0.0, 0, False, next_action=0)
        learner.update_one(0, 0, 0.0, 1, False, next_action=0)
        assert learner.eligibility()[0, 0] == expected, kind


def test_watkins_q_lambda_cuts_its_traces_after_an_exploratory_action() -> None:
    hp = {**CONSTANT, "lambda": 0.5, "traces": "accumulating"}
    learner = WatkinsQLambda(2, hp, n_states=4, seed=0)
    learner.q[2] = [2.0, 0.0]
    learner.update_one(0, 0, 1.0, 1, False, next_action=1)  # Q(0,0) = 0.5, e = 0.45
    # a' = 1 in state 2 is exploratory (Q(2,1) = 0 < 2): the update is Q-learning's with
    # the traces (δ = 1.8: Q(0,0) 0.905, Q(1,1) 0.9), then every trace is cut.
    learner.update_one(1, 1, 0.0, 2, False, next_action=1)
    assert learner.q[0, 0] == pytest.approx(0.905) and learner.q[1, 1] == pytest.approx(0.9)
    assert not learner.eligibility().any()
    assert ("a'", "exploratory: the traces are cut") in learner.last_update.notes
    # The next TD error (δ = 1 + 0.9·max Q(3,·) - 0 = 1) reaches (2,1) alone: Q = 0.5.
    learner.update_one(2, 1, 1.0, 3, False, next_action=0)
    assert learner.q[0, 0] == pytest.approx(0.905) and learner.q[2, 1] == pytest.approx(0.5)
    # Sarsa(λ) on the same steps keeps the trace of (0,0): it moves again.
    sarsa = SarsaLambda(2, hp, n_states=4, seed=0)
    sarsa.q[2] = [2.0, 0.0]
    sarsa.update_one(0, 0, 1.0, 1, False, next_action=1)
    sarsa.update_one(1, 1, 0.0, 2, False, next_action=1)
    assert np.count_nonzero(sarsa.eligibility()) == 2


def test_dyna_q_plus_adds_kappa_sqrt_tau_to_a_long_untried_pair() -> None:
    hp = {**CONSTANT, "kappa": 0.5, "planning_steps": 0}
    learner = DynaQPlus(2, hp, n_states=3, seed=2)
    # Real step 1: Q(0,0) = 0.5 (target 1). State 0 is new: its untried action 1 joins the
    # model as "back to 0, reward 0", last tried never (τ counts from the start).
    learner.update_one(0, 0, 1.0, 1, False)
    assert learner.q[0, 0] == 0.5
    assert learner.model_next[0].tolist() == [1, 0] and learner.model_reward[0, 1] == 0.0
    assert learner.last_tried[0].tolist() == [1, 0]
    learner.update_one(1, 0, 0.0, 2, True)  # real step 2 (state 1's action 1 joins too)
    learner.update_one(1, 0, 0.0, 2, True)  # real step 3
    # One planning step at real step 4 on (1,0), terminal: seed 2 draws the pair (0,1),
    # untried for τ = 4 steps: target = 0 + 0.5·√4 + 0.9·max Q(0,·) = 1 + 0.45 = 1.45,
    # Q(0,1) = 0.725.
    learner.set_hyperparameters({**hp, "planning_steps": 1})
    learner.update_one(1, 0, 0.0, 2, True)
    assert learner.q[0, 1] == pytest.approx(0.725)
    assert learner.last_update.notes == (
        ("bonus", "planning adds κ√τ (κ = 0.5): +1 (τ = 4)"),)
    assert "bonus planning adds κ√τ" in _panel(learner.last_update)


def test_prioritized_sweeping_takes_the_queue_in_order_and_sweeps_to_predecessors() -> None:
    hp = {**CONSTANT, "theta": 0.1, "planning_steps": 0}
    learner = PrioritizedSweeping(2, hp, n_states=4, seed=0)
    # No planning yet: each pair enters the queue with P = |r + γ·max Q(s',·) - Q(s,a)|
    # = |r| (Q is 0), but (2,0) with P = 0.05 <= θ stays out. Q changes only through it.
    learner.update_one(0, 0, 1.0, 1, False)
    learner.update_one(1, 1, 3.0, 2, False)
    learner.update_one(2, 0, 0.05, 3, True)
    learner.update_one(0, 1, -2.0, 3, True)
    assert learner.queue() == [(1, 1, 3.0), (0, 1, 2.0), (0, 0, 1.0)]
    assert not learner.q.any()
    # Two planning steps after (1,0) -> state 0 with r = 0 (P = 0: out):
    # 1. the top (1,1): target 3 + 0.9·max Q(2,·) = 3, Q = 1.5. Its predecessor (0,0) has
    #    P = |1 + 0.9·1.5 - 0| = 2.35 and rises past (0,1)'s 2.
    # 2. (0,0): target 2.35, Q = 1.175. Its predecessor (1,0), just modelled, enters with
    #    P = 0.9·1.175 = 1.0575.
    learner.set_hyperparameters({**hp, "planning_steps": 2})
    learner.update_one(1, 0, 0.0, 0, False)
    assert learner.q[1, 1] == 1.5 and learner.q[0, 0] == pytest.approx(1.175)
    assert learner.queue() == [(0, 1, 2.0), (1, 0, pytest.approx(1.0575))]
    record = learner.last_update
    assert [(u.state, u.action, u.target) for u in record.episode_updates] == [
        (1, 1, 3.0), (0, 0, pytest.approx(2.35))]
    assert record.notes[1] == ("queue", "2 taken from the top (P 3, 2.35), 2 left, "
                                        "the top at P 2")
    assert "P |r + γ·max Q(s',·) − Q(s,a)| = 0: (s,a) stays out (P ≤ θ)" in _panel(record)


@pytest.mark.parametrize("cls", [NStepSarsa, SarsaLambda, WatkinsQLambda, DynaQPlus,
                                 PrioritizedSweeping])
def test_the_compiled_rule_and_the_plain_rule_agree_exactly(cls) -> None:
    from tui_gym.core.engine.rules import RULES, new_log

    hp = {"learning_rate": 0.3, "discount": 0.9, "learning_rate_schedule": "constant"}
    compiled, plain = (cls(3, hp, n_states=12, seed=5) for _ in range(2))
    params = compiled.compiled_params()
    rule = RULES[type(params)].update  # the Python function the engine compiles
    assert not hasattr(rule, "py_func")
    draws = np.random.default_rng(1)
    for _ in range(600):
        s, a, s2, a2 = (int(x) for x in draws.integers(0, [12, 3, 12, 3]))
        r, ended = float(draws.normal()), bool(draws.random() < 0.1)
        compiled.learn(s, a, r, s2, ended, next_action=-1 if ended else a2)
        rule(plain.arrays(), params, plain.rng, plain.offered_ranges, s, a, r, s2, ended, False,
             -1 if ended else a2, 0.1, new_log())
    assert np.array_equal(compiled.q, plain.q) and compiled.q.any()


def test_an_optimistic_initial_value_starts_every_pair_and_draws_the_greedy_choice() -> None:
    from tui_gym.algorithms import ALGORITHMS, DoubleQLearning, QLearning

    hp = {**CONSTANT, "initial_value": 5.0}
    for cls in ALGORITHMS:
        assert cls(2, hp, n_states=3, seed=0).values([0, 2]).tolist() == [[5.0, 5.0]] * 2
    learner = QLearning(2, hp, n_states=3, seed=0)
    # target = 1 + 0.9·max Q(1,·) = 1 + 4.5 = 5.5; Q(0,1) = 5 + 0.5·0.5 = 5.25; r = 0 next:
    # Q(0,0) = 5 + 0.5·(4.5 - 5) = 4.75, so the untried action 1 now looks best.
    learner.update_one(0, 1, 1.0, 1, False)
    learner.update_one(0, 0, 0.0, 1, False)
    assert learner.q[0].tolist() == [4.75, 5.25] and learner.greedy(0) == 1
    double = DoubleQLearning(2, hp, n_states=1, seed=0)
    assert double.q_a[0, 0] == double.q_b[0, 0] == 5.0
    sparse = QLearning(2, hp, seed=0)  # rows made as keys come, and grown, start at 5 too
    for key in range(300):
        sparse.row(("key", key))
    assert (sparse.q == 5.0).all() and sparse.values([("never", 0)]).tolist() == [[5.0, 5.0]]
    loaded = QLearning.from_state(sparse.state())
    assert (loaded.q == 5.0).all()
