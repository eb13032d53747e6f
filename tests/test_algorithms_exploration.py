"""Shared exploration, hyperparameter schemas and the registry.

Epsilon-greedy (the engine's `act`) picks a random action with probability ε
and otherwise the best one, ties broken uniformly: the frequencies from a
fixed seed sit within a few standard errors of those probabilities, and
`expected_value` is the mean value under them. The epsilon schedule is
linear, then flat. Each
algorithm's schema has valid defaults and refuses bad values with a message
that names the field. The package stays free of the UI and of
Gymnasium.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from tui_gym.algorithms import ALGORITHMS, COMMON_PARAMS, QLearning, Settings, algorithm
from tui_gym.core.engine.loop import entries
from tui_gym.core.engine.rules import epsilon_at, expected_value

VALUES = np.array([1.0, 3.0, 3.0, -2.0, 3.0])  # three actions tie for the best


def _learner(values: np.ndarray, seed: int = 0) -> QLearning:
    """A learner whose row s holds `values[s]`."""
    learner = QLearning(values.shape[1], n_states=len(values), seed=seed)
    learner.q[:] = values
    return learner


def _policy(values: np.ndarray, epsilon: float) -> np.ndarray:
    """ε/n each, and the greedy share split evenly among the actions tied for the best."""
    tied = values == values.max()
    return epsilon / len(values) + (1 - epsilon) * tied / tied.sum()


def _within(counts: np.ndarray, probs: np.ndarray, n: int) -> bool:
    """Every frequency within 5 standard errors of its probability."""
    spread = 5 * np.sqrt(probs * (1 - probs) / n) + 1e-12
    return bool(np.all(np.abs(counts / n - probs) <= spread))


@pytest.mark.parametrize("epsilon", [0.0, 0.3, 1.0])
def test_epsilon_greedy_frequencies(epsilon: float) -> None:
    probs = _policy(VALUES, epsilon)
    learner = _learner(VALUES[None, :])
    tables, hp = learner.arrays(), learner.compiled_params()
    n = 20_000
    act = entries(hp).act
    picks = [act(tables, hp, learner.rng, learner.offered_ranges, 0, epsilon) for _ in range(n)]
    assert _within(np.bincount(picks, minlength=5), probs, n)
    if epsilon == 0.0:
        assert set(picks) == {1, 2, 4}  # never an action outside the tie


def test_ties_are_broken_uniformly_and_a_single_best_wins() -> None:
    values = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 5.0, 5.0, 0.0], [0.0, 0.0, 9.0, 0.0]])
    learner = _learner(values, seed=2)
    tables, hp, offered = learner.arrays(), learner.compiled_params(), learner.offered_ranges
    greedy = entries(hp).greedy
    picks = np.array([[greedy(tables, hp, learner.rng, offered, s) for _ in range(10_000)]
                      for s in range(3)])
    assert _within(np.bincount(picks[0], minlength=4), np.full(4, 0.25), 10_000)
    assert _within(np.bincount(picks[1], minlength=4), np.array([0, 0.5, 0.5, 0]), 10_000)
    assert set(picks[2].tolist()) == {2}


def test_the_expected_value_is_the_mean_under_epsilon_greedy() -> None:
    values = np.random.default_rng(3).integers(0, 3, (50, 4)).astype(float)  # many ties
    learner = _learner(values)
    tables, offered = learner.arrays(), learner.offered_ranges
    for s, row in enumerate(values):
        probs = _policy(row, 0.17)
        assert probs.sum() == pytest.approx(1.0)
        assert expected_value(tables[:1], offered, s, 0.17) == pytest.approx(probs @ row)


def test_the_epsilon_schedule_is_linear_then_flat() -> None:
    for fraction in (0.0, 0.3, 0.5, 1.0):
        settings = QLearning.hyperparameters(epsilon_start=0.9, epsilon_final=0.1,
                                             epsilon_decay_fraction=fraction, episodes=1000)
        decay = fraction * 1000
        for episode in (0, 1, 150, 299, 300, 499, 500, 999, 5000):
            expected = 0.1 if episode >= decay else 0.9 + episode / decay * (0.1 - 0.9)
            assert settings.epsilon_at(episode) == expected
    assert epsilon_at(50.0, 1.0, 0.0, 100.0) == 0.5


def test_the_learner_follows_its_schedule_and_live_changes() -> None:
    learner = QLearning(2, {"episodes": 100, "epsilon_decay_fraction": 0.5}, n_states=2, seed=0)
    assert learner.epsilon == 1.0
    learner.end_episodes(25)
    assert learner.epsilon == pytest.approx(1.0 - 0.5 * 0.95)
    learner.set_hyperparameters({**learner.hp, "epsilon_final": 0.2, "learning_rate": 0.5})
    assert learner.epsilon == pytest.approx(0.6) and learner.episode == 25  # takes effect at once
    assert learner.hp.learning_rate == 0.5


def test_common_params_keep_the_defaults_blackjack_learns_with() -> None:
    assert QLearning.settings().to_dict() == {
        "learning_rate": 0.001, "discount": 1.0, "epsilon_start": 1.0, "epsilon_final": 0.05,
        "epsilon_decay_fraction": 0.5, "episodes": 200_000, "initial_value": 0.0,
        "learning_rate_schedule": "visits",
    }
    assert [f.name for f in COMMON_PARAMS] == list(QLearning.settings())


def test_settings_parse_text_and_refuse_bad_values() -> None:
    settings = algorithm("dyna-q").settings({"learning_rate": "0.25", "planning_steps": "5",
                                             "learning_rate_schedule": " Constant "})
    assert (settings.learning_rate, settings.planning_steps) == (0.25, 5)
    assert settings["learning_rate_schedule"] == "constant"
    assert settings.replace(discount=0.5).discount == 0.5 and settings.discount == 1.0
    assert pickle.loads(pickle.dumps(settings)) == settings
    with pytest.raises(ValueError, match=r"learning_rate is out of range: 0 is not in \(0, 1\]"):
        settings.replace(learning_rate=0)
    with pytest.raises(ValueError, match="learning_rate_schedule must be one of constant, visits"):
        settings.replace(learning_rate_schedule="cosine")
    with pytest.raises(ValueError, match="unknown hyperparameter"):
        QLearning.settings({"planning_steps": 3})  # Dyna-Q's, not Q-learning's
    with pytest.raises(ValueError, match="epsilon_final"):
        QLearning.settings({"epsilon_start": 0.1, "epsilon_final": 0.2})
    with pytest.raises(AttributeError):
        settings.discount = 0.3  # type: ignore[misc]


def test_the_registry() -> None:
    names = [cls.name for cls in ALGORITHMS]
    assert names == ["q-learning", "sarsa", "expected-sarsa", "double-q", "monte-carlo", "dyna-q",
                     "n-step-sarsa", "sarsa-lambda", "q-lambda", "dyna-q-plus",
                     "prioritized-sweeping", "td0", "mc-prediction", "n-step-td", "td-lambda",
                     "offline-lambda-return"]
    assert algorithm("Expected_SARSA").name == "expected-sarsa"
    with pytest.raises(ValueError, match="unknown algorithm 'td-1'; choose one of q-learning"):
        algorithm("td-1")
    for cls in ALGORITHMS:
        assert cls.title and cls.summary and cls.formula
        fields = [f.name for f in cls.params]
        assert len(fields) == len(set(fields)) and all(f.help for f in cls.params)
        assert isinstance(cls.settings(), Settings)
    learners = [cls(2, n_states=1) for cls in ALGORITHMS]
    assert [learner.name for learner in learners if learner.next_first] == [
        "sarsa", "n-step-sarsa", "sarsa-lambda", "q-lambda"]


def test_the_package_imports_neither_textual_nor_gymnasium() -> None:
    import ast
    from pathlib import Path

    import tui_gym.algorithms as package

    for path in Path(package.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            for name in names:
                assert name.split(".")[0] not in {"textual", "gymnasium"}, (path.name, name)
