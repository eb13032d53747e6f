"""Bounded statistics and the trainer: episodes counted right, memory fixed, snapshots frozen,
on the env and on a game's model; a run cut into chunks is the same run; the rate shown is
the recent one."""

from __future__ import annotations

import dataclasses
import threading
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.wrappers import RecordEpisodeStatistics

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.algorithms import QLearning, Settings
from tui_gym.core.engine.stats import (
    EpisodeStats,
    RollingWindow,
    Series,
    StepEvent,
    TrainingSnapshot,
)
from tui_gym.core.engine.trainer import SERIES_NAMES, Trainer
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.session.session import Session

GRID = "tui_gym/GridWorld-v0"

# -- RollingWindow --------------------------------------------------------------


@pytest.mark.parametrize("size", [1, 7, 100])
def test_rolling_window_matches_numpy_through_wrap_around(size: int) -> None:
    rng = np.random.default_rng(size)
    data = rng.normal(loc=3.0, scale=2.0, size=5 * size + 3)
    window = RollingWindow(size)
    assert window.mean == 0.0 and window.std == 0.0 and window.filled == 0
    for i, value in enumerate(data, start=1):
        window.push(float(value))
        expected = data[max(0, i - size) : i]
        assert window.filled == len(expected) and window.count == i
        assert window.mean == pytest.approx(expected.mean(), rel=1e-12, abs=1e-12)
        assert window.std == pytest.approx(expected.std(), rel=1e-12, abs=1e-12)
        assert np.array_equal(window.values(), expected)  # oldest first


def test_rolling_window_does_not_drift_over_long_runs() -> None:
    window = RollingWindow(10)
    for _ in range(100_003):
        window.push(1e8)
        window.push(1e-8)
    assert window.mean == pytest.approx((1e8 + 1e-8) / 2, rel=1e-12)


def test_rolling_window_values_is_a_copy_and_size_must_be_positive() -> None:
    window = RollingWindow(3)
    window.push(1.0)
    window.values()[0] = 9.0
    assert window.values().tolist() == [1.0]
    with pytest.raises(ValueError, match="window size"):
        RollingWindow(0)


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


# -- Series ---------------------------------------------------------------------


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


def test_series_stays_within_capacity_and_covers_the_whole_run() -> None:
    series = Series(capacity=64)
    n = 100_000
    for i in range(n):
        series.push(float(i))
        assert len(series.points()) < 64
    points = np.array(series.points())
    # Each point is the mean of `span` consecutive values, so the points of a
    # linear input rise from about the start to about the end of the run.
    covered = len(points) * series.span
    assert n - series.span < covered <= n
    assert points[0] == pytest.approx((series.span - 1) / 2)
    assert points[-1] == pytest.approx(covered - (series.span + 1) / 2)
    assert points.mean() == pytest.approx((covered - 1) / 2)
    assert np.all(np.diff(points) > 0)


def test_series_of_a_constant_is_that_constant() -> None:
    series = Series(capacity=16)
    for _ in range(12_345):
        series.push(2.5)
    assert series.points() and all(p == 2.5 for p in series.points())


def test_series_keeps_every_value_until_full() -> None:
    series = Series(capacity=8)
    for v in range(7):
        series.push(float(v))
    assert series.points() == tuple(float(v) for v in range(7)) and series.span == 1
    series.push(7.0)  # full: neighbours merge
    assert series.points() == (0.5, 2.5, 4.5, 6.5) and series.span == 2


@pytest.mark.parametrize("capacity", [0, 1, 7])
def test_series_capacity_must_be_even_and_at_least_two(capacity: int) -> None:
    with pytest.raises(ValueError, match="capacity"):
        Series(capacity)


# -- the trainer ----------------------------------------------------------------


class EpisodeRecorder(gym.Wrapper):
    """Keeps the `info["episode"]` that RecordEpisodeStatistics reports at each episode end."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.episodes: list[dict[str, Any]] = []

    def step(self, action: Any) -> Any:
        result = self.env.step(action)
        info = result[4]
        if "episode" in info:
            self.episodes.append(dict(info["episode"]))
        return result


def _trainer(
    env: gym.Env,
    hp: Settings | None = None,
    seed: int = 0,
    **kwargs: Any,
) -> Trainer:
    keyer = ObservationKeyer(env.observation_space)
    agent = QLearning(int(env.action_space.n), hp, n_states=keyer.n_states, seed=seed)
    return Trainer(env, agent, keyer, seed=seed, **kwargs)


def _grid(**kwargs: Any) -> gym.Env:
    return gym.make(GRID, max_episode_steps=15, step_penalty=0.01, **kwargs)


@pytest.mark.parametrize("env_id", ["Blackjack-v1", GRID])
def test_episode_returns_and_lengths_match_record_episode_statistics(env_id: str) -> None:
    inner = _grid() if env_id == GRID else gym.make(env_id)
    recorder = EpisodeRecorder(RecordEpisodeStatistics(inner))
    trainer = _trainer(recorder, seed=4)
    ours = [trainer.run_episode() for _ in range(200)]
    theirs = recorder.episodes
    assert len(theirs) == 200
    assert [s.length for s in ours] == [int(e["l"]) for e in theirs]
    assert [s.episode_return for s in ours] == pytest.approx([float(e["r"]) for e in theirs])
    assert trainer.episodes == 200 and trainer.steps == sum(s.length for s in ours)
    if env_id == GRID:  # truncated episodes are counted too
        assert 15 in {s.length for s in ours}
        assert len({s.length for s in ours}) > 3


def test_rolling_statistics_are_the_last_episodes() -> None:
    trainer = _trainer(_grid(), seed=1, window=50)
    stats = [trainer.run_episode() for _ in range(120)]
    last = stats[-50:]
    snap = trainer.snapshot()
    assert snap.mean_return == pytest.approx(np.mean([s.episode_return for s in last]))
    assert snap.mean_length == pytest.approx(np.mean([s.length for s in last]))
    assert snap.mean_abs_td == pytest.approx(np.mean([s.mean_abs_td for s in last]))
    assert snap.last == stats[-1] and snap.window == 50


def test_memory_does_not_grow_with_episodes() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"), window=100, series_capacity=32)

    def sizes() -> list[int]:
        out = [w._values.nbytes for w in trainer.windows.values()]
        out += [len(s.points()) for s in trainer.series.values()]
        return out + [trainer.agent.q.nbytes]

    trainer.run(episodes=500)  # the windows full, each series merged several times over
    before = sizes()
    trainer.run(episodes=1_500)
    after = sizes()
    assert after[: len(SERIES_NAMES)] == before[: len(SERIES_NAMES)]
    assert all(n < 32 for n in after[len(SERIES_NAMES) : -1])
    assert after[-1] == before[-1]  # a dense table is allocated once
    assert trainer.episodes == 2_000


def test_run_episodes_runs_exactly_that_many() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"))
    assert trainer.run(episodes=37) == 37
    assert trainer.episodes == 37 and trainer.agent.episode == 37
    assert trainer.run(episodes=5) == 5 and trainer.episodes == 42
    assert trainer.latest.episodes == 42  # published at the end of the chunk
    assert not trainer.episode_in_progress()


def test_run_needs_a_way_to_stop() -> None:
    with pytest.raises(ValueError, match="episodes, seconds or a stop event"):
        _trainer(gym.make("Blackjack-v1")).run()


def test_run_for_seconds_stops() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"))
    done = trainer.run(seconds=0.0)
    assert done >= 1 and trainer.episodes == done
    assert trainer.latest.episodes == done and trainer.seconds > 0


def test_a_set_stop_event_stops_a_run() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"))
    stop = threading.Event()
    stop.set()
    done = trainer.run(stop=stop)
    assert done >= 1 and trainer.episodes == done


def test_a_stop_event_stops_a_run_on_another_thread() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"), publish_interval=0.0)
    stop, published = threading.Event(), threading.Event()
    snapshots: list[TrainingSnapshot] = []

    def on_publish(snap: TrainingSnapshot) -> None:
        snapshots.append(snap)
        published.set()

    worker = threading.Thread(target=trainer.run, kwargs={"stop": stop, "on_publish": on_publish})
    worker.start()
    assert published.wait(timeout=30), "the trainer never published"
    stop.set()
    worker.join(timeout=30)
    assert not worker.is_alive()
    assert trainer.episodes >= 1
    assert snapshots[-1].episodes == trainer.episodes
    versions = [s.version for s in snapshots]
    assert versions == sorted(versions) and len(set(versions)) == len(versions)


def test_snapshot_is_frozen_and_its_table_is_a_copy() -> None:
    trainer = _trainer(gym.make("Blackjack-v1"))
    trainer.run(episodes=300)
    snap = trainer.snapshot()
    with pytest.raises(dataclasses.FrozenInstanceError):
        snap.episodes = 0  # type: ignore[misc]
    assert not np.shares_memory(snap.q, trainer.agent.q)
    frozen_q = snap.q.copy()
    series = snap.series["return"]
    trainer.run(episodes=300)
    assert np.array_equal(snap.q, frozen_q) and not np.array_equal(trainer.agent.q, frozen_q)
    assert snap.series["return"] == series and snap.episodes == 300
    assert isinstance(series, tuple)


def test_snapshot_values_read_like_the_agent_for_sparse_tables() -> None:
    from tui_gym.core.wrappers import WrapperChoice, build_env

    env = build_env("Blackjack-v1", choices=[WrapperChoice.make("FlattenObservation")])
    trainer = _trainer(env)
    trainer.run(episodes=200)
    snap = trainer.snapshot()
    assert snap.keys is not None and len(snap.keys) == len(snap.q)
    keys = [*snap.keys[:20], ("never", "seen")]
    assert np.array_equal(snap.values(keys), trainer.agent.values(keys))


def test_same_seed_gives_identical_snapshots() -> None:
    def snap(seed: int) -> TrainingSnapshot:
        trainer = _trainer(_grid(), seed=seed, window=100)
        trainer.run(episodes=300)
        return trainer.snapshot()

    a, b, c = snap(7), snap(7), snap(8)
    assert np.array_equal(a.q, b.q)
    assert (a.episodes, a.steps, a.epsilon, a.last) == (b.episodes, b.steps, b.epsilon, b.last)
    assert (a.mean_return, a.mean_length, a.mean_abs_td) == (
        b.mean_return,
        b.mean_length,
        b.mean_abs_td,
    )
    assert a.series == b.series
    assert not np.array_equal(a.q, c.q)


def test_step_gives_events_and_finishes_episodes() -> None:
    trainer = _trainer(_grid(), seed=2)
    events: list[StepEvent] = []
    while trainer.episodes < 3:
        events.append(trainer.step())
    done = [e for e in events if e.episode_done is not None]
    assert len(done) == 3 and events[-1] is done[-1]
    for event in events:
        assert 0 <= event.action < 4
        assert (event.episode_done is not None) == (event.terminated or event.truncated)
    for before, after in zip(events, events[1:], strict=False):
        if before.episode_done is None:  # the next step starts where this one ended
            assert np.array_equal(after.observation["agent"], before.next_observation["agent"])
    end = next(i for i, e in enumerate(events) if e is done[0])
    first = events[: end + 1]
    stats = done[0].episode_done
    assert isinstance(stats, EpisodeStats)
    assert stats.length == len(first)
    assert stats.episode_return == pytest.approx(sum(e.reward for e in first))
    assert not trainer.episode_in_progress() and trainer.current_observation() is None
    trainer.step()
    assert trainer.episode_in_progress() or trainer.episodes == 4


def test_epsilon_follows_the_budget_during_training() -> None:
    hp = QLearning.hyperparameters(episodes=100, epsilon_decay_fraction=0.5, epsilon_final=0.1)
    trainer = _trainer(gym.make("Blackjack-v1"), hp)
    stats = [trainer.run_episode() for _ in range(60)]
    assert stats[0].epsilon == 1.0
    assert stats[25].epsilon == pytest.approx(hp.epsilon_at(25))
    assert stats[55].epsilon == pytest.approx(0.1)
    assert trainer.snapshot().progress == pytest.approx(0.6)
    assert trainer.remaining == 40


def test_restore_carries_counts_and_statistics() -> None:
    old = _trainer(gym.make("Blackjack-v1"))
    old.run(episodes=50)
    new = Trainer(gym.make("Blackjack-v1"), old.agent, old.keyer, seed=0)
    new.restore(old.progress())
    assert (new.episodes, new.steps) == (old.episodes, old.steps)
    assert new.latest.mean_return == old.latest.mean_return
    new.run(episodes=10)
    assert new.episodes == 60


# -- on the model -----------------------------------------------------------------


def _model_session(seed: int = 3, **hp: Any) -> Session:
    session = Session("frozenlake", hp={"episodes": 5_000, **hp}, seed=seed)
    assert session.trainer.model is not None and session.engine_reason == "model: FrozenLake"
    return session


def test_the_model_loop_runs_exactly_the_episodes_asked_for() -> None:
    trainer = _model_session().trainer
    assert trainer.run(episodes=1) == 1 and trainer.run(episodes=250) == 250
    assert trainer.episodes == trainer.agent.episode == 251
    assert trainer.latest.episodes == 251 and trainer.engine == "model"
    stop = threading.Event()
    stop.set()
    assert trainer.run(stop=stop) >= 0 and trainer.episodes == trainer.agent.episode


def test_a_run_cut_into_chunks_is_the_same_run() -> None:
    whole = _model_session()
    whole.trainer.run(episodes=3_000)
    cut = _model_session()
    for size in (1, 2, 997, 1, 1_999):
        cut.trainer.run(episodes=size)
    cut.trainer._call_steps = 7  # calls of a few transitions each, episodes carried over
    cut.trainer.run(episodes=3_000 - cut.trainer.episodes)
    assert np.array_equal(whole.agent.q, cut.agent.q)
    assert whole.trainer.steps == cut.trainer.steps
    for name, points in whole.trainer.latest.series.items():  # sums in another order
        assert cut.trainer.latest.series[name] == pytest.approx(points, rel=1e-9, abs=1e-12)
    assert whole.agent.rng.random() == cut.agent.rng.random()


def test_the_rate_shown_is_the_rate_of_the_loop_training_now() -> None:
    # Animated steps are slow (the pause between them counts as training time); at max
    # speed the rate shown must be that of the max-speed run, not the animated pace.
    trainer = Session("blackjack", seed=1).trainer
    for _ in range(4):
        trainer.step()
        trainer.seconds += 0.5
        trainer.publish()
    assert trainer.latest.episodes_per_second < 5
    trainer.run(episodes=20_000)
    assert trainer.latest.episodes_per_second > 1_000
    assert trainer.latest.episodes_per_second == pytest.approx(
        20_000 / (trainer.seconds - 2.0), rel=0.5)


def test_a_trainer_that_takes_over_shows_the_rate_of_the_run_it_took_over() -> None:
    # The app's process runner hands a run back to the app's own trainer: after a run at
    # max speed that followed two animated steps, the rate shown is the max-speed one.
    child, parent = Session("blackjack", seed=1).trainer, Session("blackjack", seed=1).trainer
    parent.step()
    parent.step()
    child.restore(parent.progress())
    child.run(episodes=20_000)
    parent.restore(child.progress())
    assert parent.latest.episodes_per_second == child.latest.episodes_per_second > 1_000
