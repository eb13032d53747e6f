"""The background runner (start, pause, one episode, speeds) and human play in the core."""

from __future__ import annotations

import time

import pytest

from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.play import HumanGame, PlayError, Tally
from tui_gym.session.runner import TrainingRunner
from tui_gym.session.session import Session
from tui_gym.session.speeds import SPEEDS


def wait_for(predicate, timeout: float = 10.0) -> bool:
    """Poll a condition with a deadline (no fixed sleeps)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.005)
    return predicate()


@pytest.fixture
def runner():
    session = Session("blackjack", hp=QLearning.hyperparameters(episodes=50_000), seed=0)
    r = TrainingRunner(session)
    yield r
    r.close()


def test_runner_trains_in_background_and_pauses(runner):
    assert runner.start()
    assert wait_for(lambda: runner.latest.episodes > 500)
    runner.pause()
    stopped_at = runner.session.trainer.episodes
    assert not runner.running
    # Paused: nothing moves while the worker is idle.
    assert runner.wait_idle()
    assert runner.session.trainer.episodes == stopped_at


def test_runner_stops_at_the_budget():
    session = Session("blackjack", hp=QLearning.hyperparameters(episodes=300), seed=0)
    r = TrainingRunner(session)
    try:
        r.start()
        assert wait_for(lambda: not r.running)
        assert session.trainer.episodes == 300
        assert r.finished
        assert not r.start()  # budget used up
    finally:
        r.close()


def test_one_episode_runs_exactly_one(runner):
    runner.run_one_episode()
    assert wait_for(lambda: runner.session.trainer.episodes == 1)
    assert runner.wait_idle()
    assert runner.session.trainer.episodes == 1


def test_animated_speed_records_each_step():
    short = (WrapperChoice.make("TimeLimit", max_episode_steps=12),)
    session = Session("gridworld", choices=short, seed=0)
    r = TrainingRunner(session, speed=len(SPEEDS) - 2)
    try:
        assert r.speed.animated
        r.run_one_episode()
        assert wait_for(lambda: session.trainer.episodes == 1, timeout=60)
        assert r.last_event is not None and r.last_event.episode_done is not None
        assert r.last_scene is not None and r.last_scene["size"] == 5
    finally:
        r.close()


def test_speed_changes_are_clamped(runner):
    assert runner.set_speed(99).name == SPEEDS[-1].name
    assert runner.set_speed(-5).name == SPEEDS[0].name
    assert runner.faster().name == SPEEDS[1].name
    assert runner.slower().name == SPEEDS[0].name


def test_a_training_error_is_reported_not_raised():
    session = Session("blackjack", seed=0)
    r = TrainingRunner(session)

    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    session.trainer.run = broken  # type: ignore[method-assign]
    try:
        r.start()
        assert wait_for(lambda: r.error is not None)
        assert "boom" in str(r.error)
        assert not r.running
    finally:
        r.close()


def test_blackjack_hand_played_by_a_person():
    game = HumanGame(Session("blackjack", seed=0), seed=7)
    first = game.reset()
    assert not first.done
    assert "??" in game.text()  # the hole card stays hidden
    step = game.step("stick")
    assert step.done and step.terminated
    assert "??" not in game.text()  # revealed at the end
    assert game.tally.episodes == 1
    with pytest.raises(PlayError, match="over"):
        game.step("hit")


def test_invalid_moves_are_play_errors():
    game = HumanGame(Session("gridworld", seed=0), seed=1)
    with pytest.raises(PlayError, match="reset"):
        game.step("up")
    game.reset()
    with pytest.raises(PlayError, match="valid actions"):
        game.step("jump")
    with pytest.raises(PlayError):
        game.step(7)


def test_gridworld_walk_to_target_uses_tutorial_mapping():
    game = HumanGame(Session("gridworld", seed=0), seed=3)
    game.reset()
    scene = game.scene()
    (ax, ay), (tx, ty) = scene["agent"], scene["target"]
    moves = ["right" if tx > ax else "left"] * abs(tx - ax)
    moves += ["up" if ty > ay else "down"] * abs(ty - ay)
    for move in moves:
        step = game.step(move)
    assert step.terminated and not step.truncated
    assert step.steps == game.first_info["distance"]


def test_time_limit_truncates_human_play():
    session = Session(
        "gridworld",
        choices=(WrapperChoice.make("TimeLimit", max_episode_steps=2),),
        seed=0,
    )
    game = HumanGame(session, seed=0)
    game.reset(options={"agent": (0, 0), "target": (4, 4)})
    first = game.step("left")  # into the wall
    assert not first.done
    last = game.step("down")  # into the other wall: the limit ends it
    assert last.truncated and not last.terminated
    assert game.tally.episodes == 1


def test_tally_interval_shrinks_with_more_hands():
    tally = Tally()
    for r in (1, -1) * 10:
        tally.add(r)
    lo, hi = tally.confidence_interval()
    assert lo < 0 < hi
    wide = hi - lo
    for r in (1, -1) * 1000:
        tally.add(r)
    lo, hi = tally.confidence_interval()
    assert hi - lo < wide / 5
    assert tally.wins == tally.losses == 1010


def slow_gridworld_runner() -> TrainingRunner:
    # The env loop throughout: max speed then goes on with the same episode.
    return TrainingRunner(Session("gridworld", seed=0, engine="env"), speed=0)


def test_a_pause_stops_an_animated_episode_mid_way_at_once():
    r = slow_gridworld_runner()
    try:
        r.run_one_episode()
        assert wait_for(lambda: r.last_event is not None)
        assert r.pause()  # returns once the worker has stopped
        trainer = r.session.trainer
        assert trainer.episode_in_progress() and trainer.episodes == 0, "it waited for the episode"
        steps = trainer.steps
        assert r.wait_idle() and not r.busy
        assert trainer.steps == steps
        r.set_speed(len(SPEEDS) - 1)
        r.run_one_episode()  # `.` again finishes the episode under way
        assert wait_for(lambda: trainer.episodes == 1 and not r.busy)
        assert trainer.last.length > r.last_event.step, "the same episode went on"
    finally:
        r.close()


def test_closing_mid_way_through_an_animated_episode_ends_the_worker_at_once():
    r = slow_gridworld_runner()
    r.run_one_episode()
    assert wait_for(lambda: r.last_event is not None)
    r.close()  # returns once the worker has ended
    assert not r.busy
    trainer = r.session.trainer
    assert trainer.episode_in_progress() and trainer.episodes == 0, "it waited for the episode"


def test_start_during_one_episode_then_pause_stops_everything():
    r = slow_gridworld_runner()
    try:
        r.run_one_episode()
        assert wait_for(lambda: r.last_event is not None)
        assert r.start() and r.running
        assert r.pause() and not r.busy
    finally:
        r.close()


def test_a_faster_speed_applies_without_waiting_out_the_slow_step():
    r = slow_gridworld_runner()
    try:
        r.start()
        assert wait_for(lambda: r.last_event is not None)
        r.set_speed(len(SPEEDS) - 1)  # max: the 0.35 s pause is cut short
        assert wait_for(lambda: r.latest.episodes > 50, timeout=5)
    finally:
        r.close()


def test_beside_a_ui_each_compiled_call_aims_at_call_seconds(monkeypatch):
    """The worker's calls of the compiled loop are longer than a headless run's: each time
    one comes back it may wait for the interpreter lock the UI's thread holds."""
    import tui_gym.core.engine.trainer as trainer_module
    from tui_gym.session import runner as runner_module

    assert runner_module.CALL_SECONDS > trainer_module.CHUNK_SECONDS
    session = Session("blackjack", hp=QLearning.hyperparameters(episodes=10**9), seed=0)
    trainer = session.trainer
    aims: list[float] = []
    chunk = trainer._chunk_model

    def noted(quota, call_seconds=trainer_module.CHUNK_SECONDS):
        aims.append(call_seconds)
        return chunk(quota, call_seconds)

    monkeypatch.setattr(trainer, "_chunk_model", noted)
    runner = TrainingRunner(session)
    try:
        assert runner.start()
        assert wait_for(lambda: len(aims) >= 3)
        runner.pause()
    finally:
        runner.close()
    assert set(aims) == {runner_module.CALL_SECONDS}
    trainer.run(episodes=10)  # headless: the trainer's own aim
    assert aims[-1] == trainer_module.CHUNK_SECONDS


def test_a_compiled_call_aims_the_next_one_at_its_length(monkeypatch):
    import tui_gym.core.engine.trainer as trainer_module

    session = Session("blackjack", hp=QLearning.hyperparameters(episodes=10**9), seed=0)
    trainer = session.trainer
    trainer.run(episodes=1)  # compiled and warm
    clock = iter([0.0, 0.002])  # the next call takes 2 ms, by this clock
    monkeypatch.setattr(trainer_module.time, "perf_counter", lambda: next(clock))
    steps = trainer._call_steps
    trainer._chunk_model(None, call_seconds=0.016)
    assert trainer._call_steps == min(steps * 8, 1 << 22)  # 8 times as long next time
