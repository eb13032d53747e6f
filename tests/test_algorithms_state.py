"""Saving and restoring every learner exactly: tables, counts, schedule, and each one's extras.

A learner's state goes through what a save file does (arrays in an `.npz`
without pickles, metadata through JSON, sparse keys as JSON lists) and comes
back equal: Double Q's second table, Dyna-Q's model and the order it tried
pairs in, Monte Carlo's counts. The restored learner then learns exactly as
the original does. Pickling (the process handover) and `assign_from` keep
everything too, and a state that does not fit is refused without a change.
"""

from __future__ import annotations

import io
import json
import pickle

import numpy as np
import pytest

from tui_gym.algorithms import ALGORITHMS, DynaQ, Learner, LearnerState, QLearning, algorithm

from .algorithms_mdp import open_grid, train

NAMES = [cls.name for cls in ALGORITHMS]
HP = {"learning_rate": 0.3, "learning_rate_schedule": "constant", "episodes": 40}


def _through_a_file(state: LearnerState) -> LearnerState:
    """What storage does: npz without pickles, JSON metadata, keys as JSON lists."""
    buffer = io.BytesIO()
    np.savez(buffer, **state.arrays)
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    meta = json.loads(json.dumps(state.meta))
    keys = None
    if state.keys is not None:
        keys = [tuple(k) if isinstance(k, list) else k
                for k in json.loads(json.dumps([list(k) for k in state.keys]))]
    return LearnerState(state.algorithm, arrays, meta, keys)


def _same_state(a: Learner, b: Learner) -> None:
    sa, sb = a.state(), b.state()
    assert sa.meta == sb.meta and sa.keys == sb.keys
    assert sa.arrays.keys() == sb.arrays.keys()
    for name, array in sa.arrays.items():
        assert array.dtype == sb.arrays[name].dtype, name
        assert np.array_equal(array, sb.arrays[name]), name
    assert (a.episode, a.epsilon) == (b.episode, b.epsilon)


@pytest.mark.parametrize("name", NAMES)
def test_a_trained_learner_survives_a_save_file_exactly(name: str) -> None:
    mdp = open_grid()
    learner = algorithm(name)(4, HP, n_states=mdp.n_states, seed=1)
    train(learner, mdp, 30)
    saved = learner.state()
    expected = {
        "q-learning": {"q", "counts", "visits"},
        "sarsa": {"q", "counts", "visits"},
        "expected-sarsa": {"q", "counts", "visits"},
        "double-q": {"q_a", "q_b", "counts_a", "counts_b", "visits"},
        "monte-carlo": {"q", "counts", "visits"},
        "dyna-q": {"q", "counts", "visits", "model_reward", "model_next", "model_terminated",
                   "model_tried"},
        "n-step-sarsa": {"q", "counts", "visits"},
        "sarsa-lambda": {"q", "counts", "visits"},
        "q-lambda": {"q", "counts", "visits"},
        "dyna-q-plus": {"q", "counts", "visits", "model_reward", "model_next",
                        "model_terminated", "model_tried", "last_tried", "model_clock"},
        "prioritized-sweeping": {"q", "counts", "visits", "model_reward", "model_next",
                                 "model_terminated", "queue_cells", "queue_priorities",
                                 "model_first_into", "model_next_into"},
    }.get(name, {"q", "counts", "visits", "v"})  # a prediction learner's V
    assert set(saved.arrays) == expected
    assert saved.meta["algorithm"] == name and saved.meta["episode"] == 30
    restored = type(learner).from_state(_through_a_file(saved), seed=99)
    _same_state(learner, restored)
    # From here on both learn the same, given the same generator state.
    restored.rng.bit_generator.state = learner.rng.bit_generator.state
    train(learner, mdp, 10)
    train(restored, mdp, 10)
    _same_state(learner, restored)


def test_double_q_keeps_both_tables_and_dyna_q_its_model() -> None:
    mdp = open_grid()
    double = algorithm("double-q")(4, HP, n_states=mdp.n_states, seed=2)
    train(double, mdp, 20)
    assert not np.array_equal(double.q_a, double.q_b)
    back = type(double).from_state(_through_a_file(double.state()))
    assert np.array_equal(back.q_b, double.q_b) and np.array_equal(back.counts_b, double.counts_b)
    dyna = DynaQ(4, {**HP, "planning_steps": 3}, n_states=mdp.n_states, seed=2)
    train(dyna, mdp, 20)
    again = DynaQ.from_state(_through_a_file(dyna.state()))
    assert np.array_equal(again.model_next, dyna.model_next)
    assert np.array_equal(again.model_reward, dyna.model_reward)
    tried = again.state().arrays["model_tried"]
    assert tried.tolist() == dyna.state().arrays["model_tried"].tolist()
    assert again.hp.planning_steps == 3


@pytest.mark.parametrize("name", NAMES)
def test_sparse_keys_grow_the_tables_and_round_trip(name: str) -> None:
    learner = algorithm(name)(3, {**HP, "discount": 0.9}, seed=0)
    rng = np.random.default_rng(0)
    keys = [(float(i) / 7, i % 3) for i in range(300)]  # more keys than the first 256 rows
    for step in range(900):
        key, next_key = keys[int(rng.integers(300))], keys[int(rng.integers(300))]
        action = learner.act(key)
        learner.update_one(key, action, float(rng.normal()), next_key, step % 9 == 8,
                           next_action=learner.act(next_key))
    assert learner.rows_used > 256 and not learner.dense  # grown past its first rows
    restored = type(learner).from_state(_through_a_file(learner.state()))
    _same_state(learner, restored)
    assert np.array_equal(restored.values(keys), learner.values(keys))
    assert restored.values([("never", "seen")]).tolist() == [[0.0, 0.0, 0.0]]


@pytest.mark.parametrize("name", NAMES)
def test_pickling_and_assign_from_keep_everything(name: str) -> None:
    mdp = open_grid()
    learner = algorithm(name)(4, HP, n_states=mdp.n_states, seed=3)
    train(learner, mdp, 15)
    copy = pickle.loads(pickle.dumps(learner))
    _same_state(learner, copy)
    target = algorithm(name)(4, HP, n_states=mdp.n_states, seed=4)
    target.assign_from(copy)
    _same_state(learner, target)
    assert target.rng.bit_generator.state == learner.rng.bit_generator.state


def test_states_that_do_not_fit_are_refused_without_a_change() -> None:
    learner = QLearning(2, n_states=4, seed=0)
    learner.q[1] = [1.0, 2.0]
    good = learner.state()
    other = DynaQ(2, n_states=4, seed=0)
    with pytest.raises(ValueError, match="q-learning learner's state, not dyna-q"):
        other.load_state(good)
    bad_cases = [
        (LearnerState("q-learning", good.arrays, {**good.meta, "n_actions": 3}), "actions"),
        (LearnerState("q-learning", good.arrays, {**good.meta, "rows": 5}), "states"),
        (LearnerState("q-learning", good.arrays, good.meta, keys=[0, 1, 2, 3]), "sparse"),
        (LearnerState("q-learning", {k: v for k, v in good.arrays.items() if k != "counts"},
                      good.meta), "no 'counts'"),
        (LearnerState("q-learning", {**good.arrays, "q": np.zeros((4, 3))}, good.meta),
         "shape"),
        (LearnerState("q-learning", good.arrays,
                      {**good.meta, "hyperparameters": {"learning_rate": 7}}), "learning_rate"),
    ]
    fresh = QLearning(2, n_states=4, seed=0)
    for state, message in bad_cases:
        with pytest.raises(ValueError, match=message):
            fresh.load_state(state)
        assert not fresh.q.any() and fresh.episode == 0
    dyna = DynaQ(2, n_states=4, seed=0)
    state = dyna.state()
    broken = LearnerState("dyna-q", {**state.arrays, "model_tried": np.array([99])}, state.meta)
    with pytest.raises(ValueError, match="model_tried"):
        dyna.load_state(broken)
    fresh.load_state(good)
    assert fresh.q[1].tolist() == [1.0, 2.0]
