"""The fast seed-batch path gives the general loop's numbers, bit for bit."""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
import numpy as np
import pytest

from tui_gym.algorithms.steps import move_toward
from tui_gym.core.experiments.fast_batch import step_size_tables
from tui_gym.core.experiments.seed_batch import SeedBatch
from tui_gym.core.mdp import FiniteMDP, model_from_env

from .seed_batches import cliff_model
from .seed_batches import seed_batch as _batch


@pytest.fixture(scope="module")
def cliff() -> FiniteMDP:
    return cliff_model()


def _same(fast: SeedBatch, general: SeedBatch) -> None:
    a, b = fast.state(), general.state()
    assert a.exact is not None and b.exact is not None
    for mine, theirs in [
        (fast.learner.q, general.learner.q),
        (fast.learner.counts, general.learner.counts),
        (fast.learner.visits, general.learner.visits),
        (a.done, b.done),
        (a.returns, b.returns),
        (a.exact, b.exact),
    ]:
        assert mine.dtype == theirs.dtype
        # Bit for bit: the same bytes, NaN where the other has NaN.
        assert mine.tobytes() == theirs.tobytes()
    # The learner's generator and epsilon are left where the general loop leaves them.
    assert fast.learner.epsilon == general.learner.epsilon
    assert fast.learner.rng.random() == general.learner.rng.random()


SETTINGS = [
    {},  # the defaults: epsilon decays (one epsilon per seed), step sizes by visits
    {"learning_rate_schedule": "constant", "learning_rate": 0.3, "epsilon_decay_fraction": 0.0},
    {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5},  # the bench's
]


@pytest.mark.parametrize("name", ["q-learning", "sarsa"])
@pytest.mark.parametrize("hp", SETTINGS)
def test_fast_path_matches_the_general_loop(
    cliff: FiniteMDP, name: str, hp: dict[str, object]
) -> None:
    fast, general = _batch(name, cliff, 4, 12, **hp), _batch(name, cliff, 4, 12, **hp)
    assert fast._fast_tables() is not None
    assert fast.run() and general.run(general=True)
    assert (fast.done == 12).all()
    _same(fast, general)


@pytest.mark.parametrize("name", ["q-learning", "sarsa"])
def test_fast_path_stops_where_the_general_loop_stops(cliff: FiniteMDP, name: str) -> None:
    fast, general = _batch(name, cliff, 4, 1000), _batch(name, cliff, 4, 1000)
    fast_calls, general_calls = iter(range(10**6)), iter(range(10**6))
    assert not fast.run(stop=lambda: next(fast_calls) >= 15)
    assert not general.run(stop=lambda: next(general_calls) >= 15, general=True)
    assert (fast.done < 1000).all()
    _same(fast, general)


@pytest.mark.parametrize("changes", range(1, 7))
def test_sarsa_stopped_just_after_episodes_end_has_drawn_what_the_general_loop_drew(
    cliff: FiniteMDP, changes: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # With epsilon constant, SARSA draws a new episode's first action as the episode starts
    # (the general loop: at the next step). Stopping looks every second step here; it stops
    # at the `changes`-th look that sees episodes ended since the last one.
    from tui_gym.core.experiments import seed_batch

    monkeypatch.setattr(seed_batch, "_CHECK_EVERY", 2)

    def stop_after(batch: SeedBatch) -> Callable[[], bool]:
        seen = [0, 0]  # episodes done at the last look, looks that saw more

        def stop() -> bool:
            done = int(batch.done.sum())
            seen[1] += done > seen[0]
            seen[0] = done
            return seen[1] >= changes
        return stop

    fast, general = (_batch("sarsa", cliff, 8, 1000, **SETTINGS[2]) for _ in range(2))
    assert not fast.run(stop=stop_after(fast))
    assert not general.run(stop=stop_after(general), general=True)
    _same(fast, general)


def test_other_learners_and_random_moves_take_the_general_loop(cliff: FiniteMDP) -> None:
    assert _batch("expected-sarsa", cliff, 2, 5)._fast_tables() is None
    slippery = gym.make("FrozenLake-v1", is_slippery=True)
    model = model_from_env(slippery)
    slippery.close()
    assert isinstance(model, FiniteMDP) and model.max_outcomes > 1
    assert _batch("q-learning", model, 2, 5)._fast_tables() is None


@pytest.mark.parametrize("schedule", ["visits", "constant"])
@pytest.mark.parametrize("rate", [0.5, 0.1, 0.3, 1.0])
def test_step_size_tables_are_the_closed_form_of_one_update(schedule: str, rate: float) -> None:
    tables = step_size_tables(rate, schedule)
    assert tables is not None
    alpha, keep = tables
    rng = np.random.default_rng(0)
    for count in [0, 1, 2, 5, len(alpha) - 1, len(alpha), 1000]:
        q = rng.normal(size=(3, 2))
        counts = np.full((3, 2), count, dtype=np.int64)
        cells = np.array([0, 3, 5])
        targets = rng.normal(size=3)
        expected = q.reshape(-1)[cells].copy()
        step = min(count, len(alpha) - 1)
        expected = keep[step] * expected + alpha[step] * targets
        move_toward(q, counts, np.zeros(3, dtype=np.int64), cells, targets, rate, schedule)
        assert q.reshape(-1)[cells].tobytes() == expected.tobytes()
