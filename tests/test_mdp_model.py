"""FiniteMDP: building from a table, checking, and the arrays derived from it."""

from __future__ import annotations

import numpy as np
import pytest

from tui_gym.core.mdp import FiniteMDP, ModelError

TABLE = {
    0: {
        0: [(0.25, 1, 0.0, False), (0.5, 1, 0.0, False), (0.25, 0, -1.0, True)],
        1: [(1.0, 0, 1.0, False), (0.0, 1, 5.0, True)],
    },
    1: {0: [(1.0, 1, 0.0, True)], 1: [(0.5, 0, 2.0, False), (0.5, 0, 3.0, False)]},
}


def arrays(**changes):
    fields = {
        "next_state": np.array([[[1, 0]], [[0, 1]]]).reshape(2, 1, 2),
        "prob": np.array([[[0.5, 0.5]], [[1.0, 0.0]]]),
        "reward": np.zeros((2, 1, 2)),
        "terminal": np.zeros((2, 1, 2), dtype=bool),
        "initial": np.array([1.0, 0.0]),
    }
    fields.update(changes)
    return fields


def test_from_table_merges_equal_outcomes_and_drops_impossible_ones():
    model = FiniteMDP.from_table(TABLE, [1.0, 0.0], action_names=("go", "stay"))
    assert (model.n_states, model.n_actions, model.max_outcomes) == (2, 2, 2)
    assert sorted(model.outcomes(0, 0)) == [(0.25, 0, -1.0, True), (0.75, 1, 0.0, False)]
    assert model.outcomes(0, 1) == [(1.0, 0, 1.0, False)]
    # Different rewards are different outcomes, even to the same state.
    assert sorted(model.outcomes(1, 1)) == [(0.5, 0, 2.0, False), (0.5, 0, 3.0, False)]
    # Padding: probability 0, back to the same state, no reward, not terminal.
    assert model.prob[0, 1, 1] == 0.0 and model.next_state[0, 1, 1] == 0
    assert not model.terminal[0, 1, 1] and model.reward[0, 1, 1] == 0.0
    assert model.action_names == ("go", "stay")
    assert model.horizon is None


def test_derived_arrays():
    model = FiniteMDP.from_table(TABLE, [0.5, 0.5])
    np.testing.assert_allclose(model.expected_reward, [[-0.25, 1.0], [0.0, 2.5]])
    np.testing.assert_allclose(model.continue_prob[0, 0].sum(), 0.75)
    assert model.continue_prob[1, 0].sum() == 0.0
    # The running total is exactly 1 from each row's last possible outcome on.
    assert (model.cumulative[:, :, -1] == 1.0).all()
    assert model.cumulative[0, 1, 0] == 1.0


def test_model_is_read_only_and_replace_checks_again():
    model = FiniteMDP.from_table(TABLE, [1.0, 0.0])
    with pytest.raises(ValueError):
        model.reward[0, 0, 0] = 3.0
    longer = model.replace(horizon=5)
    assert longer.horizon == 5 and model.horizon is None
    with pytest.raises(ModelError, match="horizon"):
        model.replace(horizon=0)
    with pytest.raises(TypeError, match="no field"):
        model.replace(gamma=0.9)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"prob": np.array([[[0.5, 0.4]], [[1.0, 0.0]]])}, "state 0, action 0 sum to 0.9"),
        ({"prob": np.array([[[1.5, -0.5]], [[1.0, 0.0]]])}, "not in \\[0, 1\\]"),
        ({"next_state": np.array([[[1, 2]], [[0, 1]]])}, "outside \\[0, 1\\]"),
        ({"next_state": np.array([[[1.0, 0.0]], [[0.0, 1.0]]])}, "integers"),
        ({"reward": np.full((2, 1, 2), np.nan)}, "not finite"),
        ({"terminal": np.zeros((2, 1, 2))}, "booleans"),
        ({"terminal": np.zeros((2, 1, 3), dtype=bool)}, "shape"),
        ({"initial": np.array([0.5, 0.6])}, "initial sums to 1.1"),
        ({"initial": np.array([1.0])}, "initial must have shape"),
        ({"horizon": 0}, "horizon must be >= 1"),
        ({"horizon": 2.5}, "horizon must be an integer"),
        ({"action_names": ("a", "b")}, "2 action names for 1 actions"),
        ({"prob": np.zeros((0, 1, 2))}, "non-empty"),
    ],
)
def test_bad_arrays_get_one_clear_message(changes, message):
    with pytest.raises(ModelError, match=message):
        FiniteMDP(**arrays(**changes))


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({0: {0: [(1.0, 0, 0.0, False)]}, 2: {}}, "no entry for state 1"),
        ({0: {0: [(1.0, 0, 0.0)]}}, "an outcome must be"),
        ({0: {0: [(0.0, 0, 0.0, False)]}}, "no possible outcome"),
        ({0: {0: [("x", 0, 0.0, False)]}}, "state 0, action 0"),
        ({0: {}}, "no actions"),
        ({0: {0: [(1.0, 0, 0.0, True)]}, 1: {1: [(1.0, 0, 0.0, True)]}}, "state 1, action 0"),
    ],
)
def test_bad_tables_get_one_clear_message(table, message):
    with pytest.raises(ModelError, match=message):
        FiniteMDP.from_table(table, np.ones(len(table)) / len(table))
