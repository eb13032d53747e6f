"""Tabular Q-learning: the update rule, the schedules, action choice, validation, the table."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from tui_gym.core.agent import (
    FIELD_BY_NAME,
    HYPERPARAMETER_FIELDS,
    Hyperparameters,
    QAgent,
)

STICK, HIT = 0, 1


def _constant(lr: float, discount: float) -> Hyperparameters:
    return Hyperparameters(learning_rate=lr, discount=discount, learning_rate_schedule="constant")


# -- the update rule ------------------------------------------------------------


def test_constant_schedule_is_the_tutorials_formula() -> None:
    # Q(s,a) <- Q(s,a) + lr * (r + gamma * (1 - terminated) * max_a' Q(s',a') - Q(s,a))
    agent = QAgent(2, _constant(0.1, 0.9), n_states=3, seed=0)
    agent.q[1] = [0.5, 2.0]

    td = agent.update(0, HIT, reward=1.0, terminated=False, next_key=1)
    assert td == pytest.approx(2.8)  # 1 + 0.9 * 2.0 - 0
    assert agent.q[0, HIT] == pytest.approx(0.28)

    td = agent.update(0, HIT, reward=-1.0, terminated=False, next_key=1)
    assert td == pytest.approx(0.52)  # -1 + 1.8 - 0.28
    assert agent.q[0, HIT] == pytest.approx(0.332)

    td = agent.update(0, STICK, reward=0.5, terminated=False, next_key=2)  # next state all zero
    assert td == pytest.approx(0.5)
    assert agent.q[0, STICK] == pytest.approx(0.05)
    assert agent.q[1].tolist() == [0.5, 2.0]  # only the updated entry moves
    assert agent.counts[0].tolist() == [1, 2]


def test_terminated_cuts_the_bootstrap_but_truncation_is_not_terminal() -> None:
    agent = QAgent(2, _constant(0.5, 1.0), n_states=2, seed=0)
    agent.q[1] = [4.0, 10.0]
    assert agent.update(0, STICK, 1.0, terminated=True, next_key=1) == pytest.approx(1.0)
    assert agent.q[0, STICK] == pytest.approx(0.5)
    # The same transition, not terminal, bootstraps from max Q(s') = 10.
    assert agent.update(0, HIT, 1.0, terminated=False, next_key=1) == pytest.approx(11.0)
    assert agent.q[0, HIT] == pytest.approx(5.5)


def test_visits_schedule_averages_then_settles_at_the_learning_rate() -> None:
    # lr = max(0.1, 1/n): the first ten updates are a plain running mean.
    agent = QAgent(2, Hyperparameters(learning_rate=0.1), n_states=1, seed=0)
    assert agent.hp.learning_rate_schedule == "visits"
    rewards = [1.0, 0.0, 1.0, 1.0]
    for r in rewards:
        agent.update(0, STICK, r, terminated=True, next_key=0)
    assert agent.q[0, STICK] == pytest.approx(0.75)  # 1 -> 0.5 -> 2/3 -> 3/4
    for r in [0.0] * 6:
        agent.update(0, STICK, r, terminated=True, next_key=0)
    assert agent.q[0, STICK] == pytest.approx(3 / 10)  # still the mean after 10 updates
    agent.update(0, STICK, 1.0, terminated=True, next_key=0)
    # n = 11: 1/11 < 0.1, so the step is 0.1, not the mean's 1/11.
    assert agent.q[0, STICK] == pytest.approx(0.3 + 0.1 * 0.7)
    assert agent.q[0, STICK] != pytest.approx(4 / 11)


def test_visits_schedule_uses_the_larger_of_lr_and_one_over_n() -> None:
    agent = QAgent(2, Hyperparameters(learning_rate=0.5), n_states=1, seed=0)
    for r in (1.0, 0.0, 1.0):
        agent.update(0, HIT, r, terminated=True, next_key=0)
    # steps 1, max(0.5, 1/2) = 0.5, max(0.5, 1/3) = 0.5: 1 -> 0.5 -> 0.75
    assert agent.q[0, HIT] == pytest.approx(0.75)
    # Counts are per (state, action): the other action starts its own average.
    agent.update(0, STICK, -1.0, terminated=True, next_key=0)
    assert agent.q[0, STICK] == pytest.approx(-1.0)


# -- epsilon --------------------------------------------------------------------


def test_epsilon_decays_linearly_over_the_fraction_then_stays_flat() -> None:
    hp = Hyperparameters(
        epsilon_start=1.0, epsilon_final=0.1, epsilon_decay_fraction=0.5, episodes=100
    )
    for episode in range(50):
        assert hp.epsilon_at(episode) == pytest.approx(1.0 - 0.9 * episode / 50)
    assert hp.epsilon_at(25) == pytest.approx(0.55)
    for episode in (50, 51, 99, 100, 10_000):
        assert hp.epsilon_at(episode) == pytest.approx(0.1)

    agent = QAgent(2, hp, n_states=1, seed=0)
    seen = [agent.epsilon]
    for _ in range(60):
        agent.end_episode()
        seen.append(agent.epsilon)
    assert seen[0] == 1.0 and seen[25] == pytest.approx(0.55)
    assert all(a >= b for a, b in itertools.pairwise(seen))
    assert seen[50:] == [pytest.approx(0.1)] * 11


def test_no_decay_means_final_epsilon_from_the_start() -> None:
    hp = Hyperparameters(epsilon_start=0.9, epsilon_final=0.2, epsilon_decay_fraction=0.0)
    assert hp.epsilon_at(0) == pytest.approx(0.2)


def test_new_hyperparameters_keep_the_table_and_move_epsilon() -> None:
    agent = QAgent(2, Hyperparameters(episodes=100), n_states=2, seed=0)
    agent.q[0] = [1.0, 2.0]
    for _ in range(30):
        agent.end_episode()
    agent.set_hyperparameters(Hyperparameters(episodes=100, epsilon_decay_fraction=0.2))
    assert agent.epsilon == pytest.approx(0.05)  # past the new, shorter decay
    assert agent.q[0].tolist() == [1.0, 2.0] and agent.episode == 30


# -- choosing actions -----------------------------------------------------------


def _binomial_bound(n: int, p: float = 0.5, sds: float = 5.0) -> float:
    return sds * math.sqrt(n * p * (1 - p))


@pytest.mark.parametrize("dense", [True, False])
def test_ties_are_broken_at_random(dense: bool) -> None:
    # Blackjack's two actions on a state never updated: both are chosen, about half each.
    agent = QAgent(2, n_states=704 if dense else None, seed=3)
    unseen = 262 if dense else (15, 10, 0)
    n = 4000
    hits = sum(agent.greedy(unseen) for _ in range(n))
    assert abs(hits - n / 2) <= _binomial_bound(n)  # 5 sd: fails by chance < 1e-6
    assert agent.greedy_actions(unseen) == (STICK, HIT)


def test_ties_among_some_actions_never_pick_a_worse_one() -> None:
    agent = QAgent(4, n_states=1, seed=0)
    agent.q[0] = [1.0, 3.0, 3.0, -2.0]
    picks = [agent.greedy(0) for _ in range(2000)]
    assert set(picks) == {1, 2}
    assert abs(picks.count(1) - 1000) <= _binomial_bound(2000)
    assert agent.greedy_actions(0) == (1, 2)


def test_a_clear_best_is_always_chosen() -> None:
    agent = QAgent(2, n_states=2, seed=0)
    agent.q[0] = [0.0, 1e-9]
    agent.q[1] = [-0.5, -0.6]
    assert {agent.greedy(0) for _ in range(500)} == {HIT}
    assert {agent.greedy(1) for _ in range(500)} == {STICK}
    assert agent.greedy_actions(0) == (HIT,)


def test_epsilon_greedy_explores_at_the_rate_epsilon() -> None:
    hp = Hyperparameters(epsilon_start=0.3, epsilon_final=0.3)
    agent = QAgent(2, hp, n_states=1, seed=5)
    agent.q[0] = [0.0, 1.0]
    n = 10_000
    sticks = sum(agent.act(0) == STICK for _ in range(n))
    # A stick happens only when exploring (0.3) and then picking stick (1/2): p = 0.15.
    assert abs(sticks - 0.15 * n) <= _binomial_bound(n, 0.15)

    greedy_only = QAgent(2, Hyperparameters(epsilon_start=0.0, epsilon_final=0.0), n_states=1)
    greedy_only.q[0] = [0.0, 1.0]
    assert {greedy_only.act(0) for _ in range(500)} == {HIT}


def test_same_seed_gives_the_same_choices() -> None:
    def choices(seed: int) -> list[int]:
        agent = QAgent(2, n_states=704, seed=seed)
        return [agent.act(key % 704) for key in range(300)]

    assert choices(11) == choices(11)
    assert choices(11) != choices(12)


def test_n_actions_must_be_positive() -> None:
    with pytest.raises(ValueError, match="n_actions"):
        QAgent(0)


# -- hyperparameter validation --------------------------------------------------

BAD_VALUES = {
    "learning_rate": [0.0, -0.1, 1.5, "fast", float("nan")],
    "discount": [-0.01, 1.01, "high", float("inf")],
    "epsilon_start": [-0.5, 1.2, "lots"],
    "epsilon_final": [-0.1, 1.1, "none"],
    "epsilon_decay_fraction": [-0.2, 1.5, "half"],
    "episodes": [0, -5, 2e9, "many", 2.5, "1.5"],
}
BAD_CASES = [(name, value) for name, values in BAD_VALUES.items() for value in values]


def test_every_field_has_bad_cases() -> None:
    assert set(BAD_VALUES) == {f.name for f in HYPERPARAMETER_FIELDS}


@pytest.mark.parametrize(("name", "value"), BAD_CASES)
def test_hyperparameter_errors_name_the_field_and_its_range(name: str, value: object) -> None:
    changes: dict[str, object] = {name: value}
    if name == "epsilon_final":
        changes["epsilon_start"] = 1.0
    with pytest.raises(ValueError) as caught:
        Hyperparameters(**changes)  # type: ignore[arg-type]
    message = str(caught.value)
    field = FIELD_BY_NAME[name]
    assert message.startswith((f"{name} must be {field.expected()}", f"{name} is out of range: "))
    assert field.describe_range() in message
    assert repr(value) in message


def test_hyperparameter_messages_read_well() -> None:
    with pytest.raises(ValueError) as caught:
        Hyperparameters(learning_rate=0)
    assert str(caught.value) == "learning_rate is out of range: 0 is not in (0, 1]"
    with pytest.raises(ValueError) as caught:
        Hyperparameters(episodes="many")  # type: ignore[arg-type]
    assert str(caught.value) == "episodes must be an integer in [1, 1000000000], got 'many'"


def test_hyperparameters_accept_the_edges_and_text_from_forms() -> None:
    hp = Hyperparameters(
        learning_rate="1",  # type: ignore[arg-type]
        discount=0,
        epsilon_start=" 0.5 ",  # type: ignore[arg-type]
        epsilon_final=0.0,
        epsilon_decay_fraction=1,
        episodes="20_000",  # type: ignore[arg-type]
    )
    assert hp.learning_rate == 1.0 and hp.discount == 0.0 and hp.epsilon_start == 0.5
    assert hp.episodes == 20_000 and isinstance(hp.episodes, int)
    assert Hyperparameters(episodes="2e3").episodes == 2000  # type: ignore[arg-type]


def test_epsilon_final_above_start_is_rejected() -> None:
    with pytest.raises(ValueError) as caught:
        Hyperparameters(epsilon_start=0.2, epsilon_final=0.5)
    message = str(caught.value)
    assert "epsilon_final" in message and "epsilon_start" in message
    assert "0.5" in message and "0.2" in message


def test_unknown_schedule_and_unknown_fields_are_rejected() -> None:
    with pytest.raises(ValueError, match="learning_rate_schedule must be one of constant, visits"):
        Hyperparameters(learning_rate_schedule="cosine")
    with pytest.raises(ValueError, match="unknown hyperparameter"):
        Hyperparameters.from_dict({"gamma": 0.9})


def test_to_dict_from_dict_and_replace() -> None:
    hp = Hyperparameters(learning_rate=0.2, episodes=500)
    assert Hyperparameters.from_dict(hp.to_dict()) == hp
    changed = hp.replace(discount=0.5)
    assert changed.discount == 0.5 and changed.learning_rate == 0.2 and hp.discount == 1.0
    with pytest.raises(ValueError, match="discount"):
        hp.replace(discount=2)


# -- reading and restoring the table --------------------------------------------


def test_values_reads_many_dense_states() -> None:
    agent = QAgent(2, n_states=4)
    agent.q[:] = np.arange(8.0).reshape(4, 2)
    out = agent.values([3, 0, 3])
    assert out.tolist() == [[6.0, 7.0], [0.0, 1.0], [6.0, 7.0]]
    out[0, 0] = 99.0
    assert agent.q[3, 0] == 6.0  # a copy
    assert agent.values([]).shape == (0, 2)


def test_values_reads_sparse_states_with_zeros_for_unseen_ones() -> None:
    agent = QAgent(2, _constant(1.0, 1.0), seed=0)
    agent.update((1, 2), HIT, 3.0, terminated=True, next_key=None)
    agent.update((5, 5), STICK, -1.0, terminated=True, next_key=None)
    out = agent.values([(5, 5), (9, 9), (1, 2)])
    assert out.tolist() == [[-1.0, 0.0], [0.0, 0.0], [0.0, 3.0]]
    assert agent.states_seen == 2


def test_sparse_table_grows_past_its_first_block() -> None:
    agent = QAgent(3, _constant(1.0, 1.0), seed=0)
    for i in range(600):
        agent.update(("s", i), i % 3, float(i), terminated=True, next_key=None)
    q, keys = agent.table()
    assert q.shape == (600, 3) and keys is not None and len(keys) == 600
    assert keys[599] == ("s", 599) and q[599, 599 % 3] == 599.0
    assert agent.values([("s", 300)])[0, 0] == 300.0


def _train_a_little(agent: QAgent, keys: list, seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(500):
        s, s2 = keys[rng.integers(len(keys))], keys[rng.integers(len(keys))]
        agent.update(s, int(rng.integers(2)), float(rng.normal()), bool(rng.random() < 0.3), s2)


@pytest.mark.parametrize("dense", [True, False])
def test_table_and_load_table_round_trip_with_counts(dense: bool) -> None:
    keys = list(range(20)) if dense else [(i, i % 3) for i in range(20)]
    n_states = 20 if dense else None
    original = QAgent(2, n_states=n_states, seed=0)
    _train_a_little(original, keys, seed=1)
    q, table_keys = original.table()
    counts = original.update_counts()
    assert (table_keys is None) == dense
    assert counts.shape == q.shape and counts.sum() == 500

    restored = QAgent(2, n_states=n_states, seed=0)
    restored.load_table(q, table_keys, counts)
    assert np.array_equal(restored.values(keys), original.values(keys))
    assert np.array_equal(restored.update_counts(), counts)
    assert restored.table()[1] == table_keys
    assert all(restored.greedy_actions(k) == original.greedy_actions(k) for k in keys)
    # The counts carry on: the "visits" step sizes of both agents stay in step.
    _train_a_little(original, keys, seed=2)
    _train_a_little(restored, keys, seed=2)
    assert np.array_equal(restored.values(keys), original.values(keys))


def test_table_is_a_copy() -> None:
    agent = QAgent(2, n_states=3)
    q, _ = agent.table()
    q[0, 0] = 5.0
    assert agent.q[0, 0] == 0.0


def test_load_table_rejects_tables_that_do_not_fit() -> None:
    dense = QAgent(2, n_states=3)
    with pytest.raises(ValueError, match="one row per state"):
        dense.load_table(np.zeros((4, 2)), None)
    with pytest.raises(ValueError, match="shape"):
        dense.load_table(np.zeros((3, 5)), None)
    with pytest.raises(ValueError, match="sparse"):
        dense.load_table(np.zeros((3, 2)), [(0,), (1,), (2,)])
    with pytest.raises(ValueError, match="update counts"):
        dense.load_table(np.zeros((3, 2)), None, np.zeros((2, 2)))
    sparse = QAgent(2)
    with pytest.raises(ValueError, match="differ in number"):
        sparse.load_table(np.zeros((3, 2)), [(0,), (1,)])


def test_load_table_without_counts_treats_learned_values_as_settled() -> None:
    agent = QAgent(2, Hyperparameters(learning_rate=0.1), n_states=1)
    agent.load_table(np.array([[1.0, 0.0]]), None)
    agent.update(0, STICK, 0.0, terminated=True, next_key=0)
    assert agent.q[0, STICK] == pytest.approx(0.9)  # the floor, not a fresh 1/1 average
    agent.update(0, HIT, 2.0, terminated=True, next_key=0)
    assert agent.q[0, HIT] == pytest.approx(2.0)  # never-learned entries still start fresh
