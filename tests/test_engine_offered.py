"""The engine honours the actions each state offers: exploration draws only those, and
the greedy choice, the max and the ε-greedy expectation range over them, in the compiled
loop, in the env loop and from Python; a game that offers every action runs as before."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.algorithms import DoubleQLearning, ExpectedSarsa, QLearning, algorithm
from tui_gym.core.engine import loop
from tui_gym.core.engine.seeds import play_learner
from tui_gym.envs.max_bias import A, B, offered
from tui_gym.games import game_named
from tui_gym.session.session import Session

CONSTANT = {"learning_rate": 0.5, "discount": 0.9, "learning_rate_schedule": "constant"}
# Row 1 offers actions 1 and 2; action 0, which it does not offer, holds the best value.
VALUES = np.array([[0.0, 0.0, 0.0], [5.0, 1.0, 2.0]])
MASK = np.array([[True, True, True], [False, True, True]])


def _masked(cls: type, hp: dict | None = None, seed: int = 0) -> object:
    learner = cls(3, {**CONSTANT, **(hp or {})}, n_states=2, seed=seed)
    for name in learner.value_tables:
        getattr(learner, name)[:] = VALUES
    learner.offer(MASK)
    return learner


@pytest.mark.parametrize("engine", ["model", "env"])
@pytest.mark.parametrize("name", ["q-learning", "double-q"])
def test_an_action_a_state_does_not_offer_is_never_taken(engine: str, name: str) -> None:
    # B offers 3 of its 10 actions; A offers left and right. Exploring half the time.
    session = Session("tui_gym/MaxBias-v0", algorithm=name, seed=7, engine=engine,
                      env_kwargs={"actions": 3},
                      hp={"epsilon_start": 0.5, "epsilon_final": 0.5, "episodes": 600})
    try:
        session.trainer.run(episodes=600)
        taken = session.agent.update_counts() > 0
        mask = offered(3)
        assert not (taken & ~mask).any()
        assert taken[A, :2].all() and taken[B, 2:5].all()  # every offered one is tried
    finally:
        session.env.close()


def test_the_agents_greedy_choice_and_ties_stay_among_the_offered_actions() -> None:
    learner = _masked(QLearning, seed=1)
    assert {learner.greedy(1) for _ in range(50)} == {2}
    assert learner.greedy_actions(1) == (2,)
    learner.epsilon = 1.0
    picks = np.bincount([learner.act(1) for _ in range(4000)], minlength=3)
    assert picks[0] == 0 and abs(picks[1] - 2000) < 5 * np.sqrt(1000)


def test_q_learnings_max_skips_an_action_the_state_does_not_offer() -> None:
    learner = _masked(QLearning)
    learner.learn(0, 0, 0.5, 1, False)
    # target = 0.5 + 0.9·max(Q(1,1), Q(1,2)) = 0.5 + 0.9·2 = 2.3 (not 0.5 + 0.9·5)
    assert learner.q[0, 0] == pytest.approx(0.5 * 2.3)


def test_expected_sarsas_expectation_is_over_the_offered_actions() -> None:
    learner = _masked(ExpectedSarsa)
    learner.epsilon = 0.2
    learner.learn(0, 0, 0.5, 1, False)
    # Σ π Q(1,·) = ε·(1 + 2)/2 + (1 - ε)·2 = 0.3 + 1.6 = 1.9; target 0.5 + 0.9·1.9 = 2.21
    assert learner.q[0, 0] == pytest.approx(0.5 * 2.21)


def test_double_qs_argmax_is_over_the_offered_actions() -> None:
    learner = _masked(DoubleQLearning)
    learner.q_b[1] = [10.0, 20.0, 30.0]  # what the other table says of the chosen action
    learner.q_a[1] = [5.0, 1.0, 2.0]
    learner.learn(0, 0, 0.0, 1, False, explain=True)
    record = learner.last_update
    assert record is not None and record.target_action == 2
    # The coin picked one table; the other one values the picked one's argmax over {1, 2}.
    evaluated = learner.q_b if record.table == "A" else learner.q_a
    assert record.target == pytest.approx(0.9 * evaluated[1, 2])


def test_an_offer_of_every_action_is_no_mask_and_a_row_offering_none_offers_all() -> None:
    learner = QLearning(3, n_states=2)
    learner.offer(np.ones((2, 3), dtype=bool))
    assert learner.offered is None and learner.offered_ranges.shape == (0, 2)
    learner.offer(np.array([[False, False, False], [True, True, False]]))
    assert learner.offered is not None and learner.offered[0].all()
    assert learner.offered_ranges.tolist() == [[0, 3], [0, 2]]
    with pytest.raises(ValueError, match="do not fit"):
        learner.offer(np.ones((3, 3), dtype=bool))
    with pytest.raises(ValueError, match=r"one run of actions \(row 1 offers \[0, 2\]"):
        learner.offer(np.array([[True, True, True], [True, False, True]]))


@pytest.mark.parametrize("name", ["q-learning", "double-q"])
def test_every_row_offering_everything_plays_the_very_run_of_no_mask(name: str) -> None:
    model = loop.ModelArrays.of(game_named("max-bias").base_model({}))
    hp = {"epsilon_start": 0.3, "epsilon_final": 0.3, "episodes": 400}
    plain, masked = (algorithm(name)(12, hp, n_states=4, seed=11) for _ in range(2))
    # A range per row, each every action (unsigned, as the learner's own bounds are).
    masked.offered_ranges = np.tile(np.array([0, 12], dtype=np.uint32), (4, 1))
    runs = [play_learner(x, model, 400, (400,)) for x in (plain, masked)]
    assert np.array_equal(runs[0][0], runs[1][0])
    assert np.array_equal(runs[0][1][0], runs[1][1][0])


def test_the_exact_reference_values_the_greedy_policy_among_the_offered_actions() -> None:
    session = Session("tui_gym/MaxBias-v0", algorithm="q-learning", seed=0)
    try:
        q = np.zeros((4, 12))
        # Left is A's best offered action (worth -0.1); the actions A does not offer look
        # better still, and would count as right (worth 0) if the greedy policy took them.
        q[A] = [0.5, 0.0] + [1.0] * 10
        found = session.game.oracle.reference(q, session.env_kwargs)
        assert found.figures["exact_value"] == pytest.approx(-0.1)
    finally:
        session.env.close()


def test_the_play_views_greedy_actions_are_among_the_offered_ones() -> None:
    session = Session("tui_gym/MaxBias-v0", algorithm="q-learning", seed=0,
                      env_kwargs={"actions": 3})
    try:
        agent = session.agent
        agent.q[B] = [0.0, 0.0, -0.3, -0.2, -0.2] + [0.0] * 7  # b4 to b10: not offered
        agent.visits[B] = 1
        found = session.greedy_actions_for(B)
        assert found is not None and found[0] == (3, 4)
    finally:
        session.env.close()


def test_the_heatmap_shows_the_max_and_greedy_move_among_the_offered_actions() -> None:
    session = Session("tui_gym/MaxBias-v0", algorithm="q-learning", seed=0)
    try:
        agent = session.agent
        agent.q[A] = [-0.5, -0.2] + [1.0] * 10  # A offers left and right only
        agent.q[B] = [2.0, 2.0, -0.3, -0.1] + [-0.4] * 8  # B offers b1 to b10
        agent.visits[[A, B]] = 1
        panel = session.heatmaps()[0]
        at = {label: float(value) for label, value in zip(panel.labels[0], panel.values[0],
                                                          strict=True) if label != "★"}
        assert at == {"→": pytest.approx(-0.2), "b2": pytest.approx(-0.1)}, at
    finally:
        session.env.close()
