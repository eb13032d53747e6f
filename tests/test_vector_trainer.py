"""Tests for `tui_gym.core.vector.trainer`: the vector engine driving a learner.

The batched statistics are checked against one-by-one pushes; then the
trainer itself, with Q-learning: it learns Blackjack to within 0.005 of the exact optimum and
GridWorld to shortest paths, finishes exactly the episodes asked for, gives
the same table for the same seeds however a run is sliced, and keeps its
memory fixed.
"""

from __future__ import annotations

import threading
import tracemalloc

import numpy as np
import pytest

from tests.game_support import form_of
from tui_gym.algorithms import Learner, QLearning, Settings
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.stats import RollingWindow, Series
from tui_gym.core.training import Engine, Trainer
from tui_gym.core.vector import (
    NoBatchedForm,
    VectorTrainer,
    make_vector_trainer,
)
from tui_gym.core.wrappers import WrapperChoice, build_env
from tui_gym.games import game_for
from tui_gym.session.session import default_settings

BLACKJACK = "Blackjack-v1"
GRID = "tui_gym/GridWorld-v0"


FORM = game_for("Blackjack-v1").batched_form({"natural": False, "sab": False})


def _agent(env_id: str, hp: Settings | None = None, seed: int = 0, **kwargs):
    env = build_env(env_id, kwargs)
    keyer = ObservationKeyer(env.observation_space)
    agent = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=seed)
    return env, agent, keyer


# --- batched statistics ----------------------------------------------------------


@pytest.mark.parametrize("size", [1, 7, 100])
def test_window_many_equals_pushing_one_by_one(size: int) -> None:
    rng = np.random.default_rng(size)
    one, many = RollingWindow(size), RollingWindow(size)
    for chunk in (3, 0, 1, 250, 5, 99, 1000, 2):
        values = rng.normal(size=chunk)
        expected = []
        for v in values:
            one.push(float(v))
            expected.append(one.mean)
        means = many.push_many(values)
        np.testing.assert_allclose(means, expected, rtol=1e-9, atol=1e-12)
        assert many.count == one.count and many.filled == one.filled
        np.testing.assert_allclose(many.values(), one.values())
        assert many.mean == pytest.approx(one.mean, abs=1e-12)


def test_series_many_equals_pushing_one_by_one() -> None:
    rng = np.random.default_rng(0)
    one, many = Series(8), Series(8)
    for chunk in (1, 3, 0, 17, 2, 64, 5, 300, 1, 1000):
        values = rng.normal(size=chunk)
        for v in values:
            one.push(float(v))
        many.push_many(values)
        assert many.span == one.span
        np.testing.assert_allclose(many.points(), one.points(), rtol=1e-9, atol=1e-12)
        assert many._acc_n == one._acc_n
        assert many._acc == pytest.approx(one._acc, abs=1e-9)


# --- training -------------------------------------------------------------------


def _blackjack_gap(agent: Learner, keyer: ObservationKeyer) -> float:
    game = game_for(BLACKJACK)
    keys = [keyer.key(obs) for obs in game.states.base_observations({})]
    return game.oracle.reference(agent.values(keys), {}).figures["gap"]


def test_learns_blackjack_to_within_0_005_of_the_optimum() -> None:
    env, agent, keyer = _agent(BLACKJACK, QLearning.hyperparameters(episodes=500_000), seed=3)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=3)
    assert trainer.run(episodes=500_000) == 500_000
    assert agent.episode == 500_000 and trainer.episodes == 500_000
    assert agent.epsilon == agent.hp.epsilon_at(500_000)
    assert _blackjack_gap(agent, keyer) < 0.005
    assert trainer.latest.engine == "vector" and trainer.latest.episodes == 500_000
    assert -0.2 < trainer.latest.mean_return < 0.1


def test_learns_gridworld_shortest_paths() -> None:
    profile = game_for(GRID)
    hp = default_settings(profile, "q-learning")
    env, agent, keyer = _agent(GRID, hp, seed=1, size=5)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=1)
    trainer.run(episodes=hp.episodes)
    keys = [keyer.key(obs) for obs in profile.states.base_observations({"size": 5})]
    reference = profile.oracle.reference(agent.values(keys), {"size": 5})
    fraction = reference.figures["optimal_pair_fraction"]
    assert fraction > 0.95
    assert trainer.windows["length"].mean < 8  # shortest paths on 5x5 average 3.3 steps


def test_same_seeds_give_the_same_table_however_the_run_is_sliced() -> None:
    def train(seconds: float | None) -> VectorTrainer:
        env, agent, keyer = _agent(BLACKJACK, QLearning.hyperparameters(episodes=30_000), seed=5)
        trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=5, num_envs=256)
        while trainer.remaining:  # as the runner does: time slices of what remains
            trainer.run(episodes=trainer.remaining, seconds=seconds)
        return trainer

    whole, sliced = train(None), train(0.001)
    assert whole.episodes == sliced.episodes == 30_000
    assert (whole.agent.q == sliced.agent.q).all()
    assert (whole.agent.counts == sliced.agent.counts).all()
    assert whole.windows["return"].mean == sliced.windows["return"].mean
    env, agent, keyer = _agent(BLACKJACK, QLearning.hyperparameters(episodes=30_000), seed=6)
    VectorTrainer(env, agent, keyer, form=form_of(env), seed=6, num_envs=256).run(episodes=30_000)
    assert not (agent.q == whole.agent.q).all()


def test_runs_finish_exactly_the_episodes_asked_for() -> None:
    env, agent, keyer = _agent(GRID, size=4)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=0, num_envs=64)
    assert trainer.run(episodes=1) == 1
    assert trainer.run(episodes=10) == 10
    assert trainer.episode_in_progress()  # envs keep playing: games carry over to the next run
    assert trainer.run(episodes=1000) == 1000
    assert trainer.run_episode().length >= 1
    assert trainer.episodes == agent.episode == 1012
    # The quota steps the oldest episodes, so no result waits on an older one.
    assert trainer.held == 0 and trainer.windows["return"].count == 1012
    stop = threading.Event()
    stop.set()
    finished = trainer.run(stop=stop)  # one batch step: all 64 grids start, few finish
    assert finished < 64 and trainer.episode_in_progress()
    assert trainer.run(episodes=5) == 5  # the games in progress count towards a quota
    assert trainer.episodes == agent.episode == 1017 + finished
    with pytest.raises(ValueError):
        trainer.run()


def test_memory_stays_bounded() -> None:
    env, agent, keyer = _agent(BLACKJACK, seed=2)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=2, num_envs=1024,
                            series_capacity=64)
    trainer.run(episodes=50_000)
    tracemalloc.start()
    before, _ = tracemalloc.get_traced_memory()
    trainer.run(episodes=100_000)
    after, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert after - before < 200_000  # bytes: snapshots and buffers, nothing per episode
    assert all(len(s.points()) < 64 for s in trainer.series.values())
    assert all(w.filled == 1000 for w in trainer.windows.values())


def test_an_engine_beside_the_scalar_trainer() -> None:
    env, agent, keyer = _agent(BLACKJACK, seed=4)
    scalar = Trainer(env, agent, keyer, seed=4)
    scalar.run(episodes=200)
    vector = VectorTrainer(env, agent, keyer, form=form_of(env), seed=4, num_envs=128)
    vector.adopt_progress(scalar)
    assert vector.episodes == 200 and vector.latest.episodes == 200
    published = []
    vector.publish_interval = 0.0
    vector.run(episodes=5_000, on_publish=published.append)
    assert vector.episodes == agent.episode == 5_200
    assert published and published[-1] is vector.latest
    assert [s.version for s in published] == sorted(s.version for s in published)
    assert vector.remaining == agent.hp.episodes - 5_200
    assert vector.current_observation() is None
    # Engines compose with the learner: neither stands in for the other.
    assert isinstance(vector, Engine) and not isinstance(vector, Trainer)
    assert not hasattr(vector, "step")
    back = Trainer(env, agent, keyer, seed=4)
    back.adopt_progress(vector)
    back.run(episodes=10)
    assert back.episodes == 5_210 and back.windows["return"].count == 5_210


def test_wrappers_shape_the_rewards_and_unbatchable_ones_refuse() -> None:
    env, agent, keyer = _agent(BLACKJACK, seed=0)
    choices = [WrapperChoice.make("StepPenalty", penalty=1.0)]
    trainer = make_vector_trainer(BLACKJACK, {}, choices, agent, keyer, form=FORM, seed=0,
                                  num_envs=256)
    trainer.run(episodes=20_000)
    # Every step costs 1, on top of a Blackjack return in [-1, 1].
    returns = trainer.windows["return"].values()
    lengths = trainer.windows["length"].values()
    assert (returns <= 1.0 - lengths + 1e-9).all() and (returns >= -1.0 - lengths - 1e-9).all()
    with pytest.raises(NoBatchedForm, match="StickyAction"):
        make_vector_trainer(BLACKJACK, {}, [WrapperChoice.make("StickyAction")], agent, keyer,
                            form=FORM)
    sparse = QLearning(2, seed=0)
    with pytest.raises(ValueError, match="dense"):
        VectorTrainer(env, sparse, keyer, form=form_of(env))


def test_the_last_window_is_not_skewed_towards_long_episodes() -> None:
    # A run must not end by waiting for its longest games: the rolling window
    # of the last 1,000 episodes should look like the run as a whole.
    env, agent, keyer = _agent(BLACKJACK, QLearning.hyperparameters(episodes=60_000), seed=0)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=0)
    trainer.run(episodes=60_000)
    lengths = trainer.windows["length"].values()
    overall = trainer.steps / trainer.episodes
    # Within 5 standard errors of the window mean (from the window's own spread).
    bound = 5 * lengths.std(ddof=1) / np.sqrt(len(lengths))
    assert abs(lengths.mean() - overall) < bound


# --- curves in the order episodes start -------------------------------------------------


@pytest.mark.parametrize(("env_id", "kwargs"), [(GRID, {"size": 5}), (BLACKJACK, {})])
def test_curves_begin_with_an_unbiased_sample(env_id: str, kwargs: dict) -> None:
    """Thousands of games start at once and the short ones finish first; a curve that
    took them in that order would begin on the shortest episodes. Under a random
    policy every episode is alike, so the first thousand recorded must look like
    the rest."""
    hp = QLearning.hyperparameters(episodes=100_000, epsilon_start=1.0, epsilon_final=1.0)
    env, agent, keyer = _agent(env_id, hp, **kwargs)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=0, num_envs=2048, window=1,
                            series_capacity=1 << 16)  # one point per episode, in order
    trainer.run(episodes=30_000)
    lengths = np.array(trainer.series["length"].points())
    assert len(lengths) + trainer.held == trainer.episodes == 30_000
    first, rest = lengths[:1000], lengths[5000:]
    tolerance = 5 * rest.std() / np.sqrt(len(first))
    assert abs(first.mean() - rest.mean()) < tolerance, (first.mean(), rest.mean())
    returns = np.array(trainer.series["return"].points())
    assert abs(returns[:1000].mean() - returns[5000:].mean()) < 5 * returns.std() / np.sqrt(1000)


def test_results_wait_for_earlier_episodes_and_one_episode_is_the_oldest() -> None:
    env, agent, keyer = _agent(GRID, size=5)
    trainer = VectorTrainer(env, agent, keyer, form=form_of(env), seed=1, num_envs=64)
    stop = threading.Event()
    stop.set()
    finished = 0
    while trainer.held == 0 or finished == 0:  # a short episode finishes before an older one
        finished += trainer.run(stop=stop)
    assert trainer.windows["return"].count + trainer.held == trainer.episodes
    recorded = trainer.windows["return"].count
    while trainer.held:  # one episode at a time: always the oldest, which releases the rest
        trainer.run(episodes=1)
        assert trainer.windows["return"].count > recorded
        recorded = trainer.windows["return"].count
    assert recorded == trainer.episodes
