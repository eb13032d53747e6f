"""The process runner: a child process that trains, hands the agent back, and can fail.

Each test drives a real child process. Every wait polls a condition with a
deadline (the runner takes in what the child says whenever it is asked).
"""

from __future__ import annotations

import collections
import multiprocessing.process
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games import game_for
from tui_gym.session import process_runner
from tui_gym.session.process_runner import ProcessRunner
from tui_gym.session.runner import SPEEDS
from tui_gym.session.session import Session, default_settings

from .test_runner_and_play import wait_for

DEADLINE = 60.0  # only reached when something is broken; a loaded machine starts a child slowly


@pytest.fixture
def blackjack_runner():
    hp = QLearning.hyperparameters(episodes=10_000_000)
    runner = ProcessRunner(Session("blackjack", hp=hp, seed=0))
    yield runner
    runner.close()


def reaped(pid: int) -> bool:
    return not Path(f"/proc/{pid}").exists()


def why(runner: ProcessRunner) -> str:
    """What a runner that trains nothing is doing (its error, child, the server's warmer)."""
    warmer = process_runner._warmer
    return (f"error {runner.error!r}; child {runner._child}; pending {runner._pending}; "
            f"warmer alive {warmer is not None and warmer.is_alive()}")


def test_a_stopped_child_is_replaced_and_the_agent_kept(blackjack_runner, monkeypatch) -> None:
    runner = blackjack_runner
    runner.start()
    assert wait_for(lambda: runner.latest.episodes > 1000, DEADLINE), why(runner)
    runner.pause(wait=True)
    kept = runner.session.trainer.episodes
    runner.start()
    stopped = runner.child_pid
    # A short silence ends the stopped child; only while it is stopped: on a busy machine
    # a child that runs may be silent for longer than that.
    with monkeypatch.context() as short:
        short.setattr(process_runner, "HANG_SECONDS", 0.5)
        os.kill(stopped, signal.SIGSTOP)
        assert wait_for(lambda: runner.error is not None, DEADLINE)
    assert "stopped answering" in str(runner.error)
    assert not runner.running
    assert reaped(stopped)
    assert runner.session.trainer.episodes == kept
    assert runner.start()
    assert wait_for(lambda: runner.latest.episodes > kept + 1000, DEADLINE), why(runner)


def test_a_child_that_keeps_dying_turns_training_off(blackjack_runner, monkeypatch) -> None:
    monkeypatch.setattr(process_runner, "RESPAWN_LIMIT", 1)
    runner = blackjack_runner
    dead = runner.child_pid
    os.kill(dead, signal.SIGKILL)
    assert wait_for(lambda: runner.error is not None, DEADLINE)
    assert "training is off" in str(runner.error) and "--runner thread" in str(runner.error)
    assert reaped(dead)
    assert not runner.start()
    assert runner.child_pid is None


def test_a_child_that_cannot_be_replaced_turns_training_off(blackjack_runner,
                                                             monkeypatch) -> None:
    """A dead child whose successor cannot start (as when the terminal and the process
    group went while the app ends: the resource tracker's descriptors are gone) turns
    training off with a message; the caller never sees the exception."""
    runner = blackjack_runner
    dead = runner.child_pid
    assert dead is not None

    def cannot_start(*_: object) -> None:
        raise ValueError("bad value(s) in fds_to_keep")

    monkeypatch.setattr(process_runner, "_Child", cannot_start)
    os.kill(dead, signal.SIGKILL)
    assert wait_for(lambda: runner.error is not None, DEADLINE)
    message = str(runner.error)
    assert "a new one could not start (bad value(s) in fds_to_keep)" in message
    assert "training is off" in message
    assert not runner.start() and not runner.running


def test_a_rebuild_that_keeps_the_agent_loses_no_episode() -> None:
    hp = default_settings(game_for("gridworld"), "q-learning").replace(episodes=10_000_000)
    session = Session("gridworld", hp=hp, seed=0)
    runner = ProcessRunner(session)
    try:
        runner.start()
        assert wait_for(lambda: runner.latest.episodes > 2000, DEADLINE), why(runner)
        seen = runner.latest.episodes
        runner.pause(wait=False)  # as the app does: no waiting on the child
        report = session.rebuild(choices=(WrapperChoice.make("TimeLimit", max_episode_steps=50),))
        assert report.kept_agent
        runner.start()
        assert wait_for(lambda: runner.latest.episodes > seen + 2000, DEADLINE), why(runner)
        runner.pause(wait=True)
        assert session.trainer.episodes > seen + 2000
        assert session.agent.episode == session.trainer.episodes
    finally:
        runner.close()


def test_one_animated_episode_streams_every_step_from_the_child() -> None:
    short = (WrapperChoice.make("TimeLimit", max_episode_steps=12),)
    session = Session("gridworld", choices=short, seed=0)
    runner = ProcessRunner(session, speed=len(SPEEDS) - 2)  # animated (fast)
    try:
        runner.run_one_episode()
        steps: list[int] = []

        def episode_over() -> bool:
            event = runner.last_event
            if event is not None and (not steps or steps[-1] != event.step):
                steps.append(event.step)
            return not runner.busy

        assert wait_for(episode_over, 60)
        assert session.trainer.episodes == 1
        assert session.trainer.engine == "env", "the session carries on as the child left it"
        assert steps == sorted(steps) and len(steps) >= 2
        last = runner.last_event
        assert last is not None and last.episode_done is not None
        assert last.episode == 1 and last.step == last.episode_done.length
        assert runner.last_scene is not None and runner.last_scene["size"] == 5
    finally:
        runner.close()


def test_a_closed_child_ends_by_itself(monkeypatch) -> None:
    killed: list[int | None] = []
    real_kill = multiprocessing.process.BaseProcess.kill

    def kill(process) -> None:
        killed.append(process.pid)
        real_kill(process)

    monkeypatch.setattr(multiprocessing.process.BaseProcess, "kill", kill)
    # Time enough for any machine: the child must quit when asked, not be killed.
    monkeypatch.setattr(process_runner, "EXIT_SECONDS", DEADLINE)
    runner = ProcessRunner(Session("blackjack", seed=0))
    runner.start()
    assert wait_for(lambda: runner.latest.episodes > 0, DEADLINE), why(runner)
    child = runner.child_pid
    assert child is not None
    runner.close(wait=True)
    # (An earlier test's child may still be reaped in the background: only this one counts.)
    assert reaped(child) and child not in killed
    runner.close(wait=True)  # again: nothing left to end
    assert child not in killed


class SlowPipe:
    """A pipe end that closes as a `multiprocessing.Connection` does (is it open? then close
    it), with time between the two for another thread to come in."""

    def __init__(self) -> None:
        self.handle: int | None = 3
        self.closes = 0

    def close(self) -> None:
        if self.handle is not None:
            time.sleep(0.05)
            self.closes += 1
            self.handle = None


def test_two_reaps_at_once_close_the_pipe_once() -> None:
    # A switch's reaper in the background and the app's exit: a second close of the same
    # descriptor would close whatever file has taken its number.
    child = process_runner._Child(collections.deque(), threading.Event())
    child.end(wait=True)
    child.conn = pipe = SlowPipe()  # type: ignore[assignment]
    reapers = [threading.Thread(target=child.reap) for _ in range(2)]
    for reaper in reapers:
        reaper.start()
    for reaper in reapers:
        reaper.join(DEADLINE)
    assert pipe.closes == 1


@pytest.mark.parametrize("methods", [["forkserver", "spawn"], ["spawn"]],
                         ids=["fork-server", "no-fork-server"])
def test_a_child_trains_whether_it_forks_from_the_server_or_is_spawned(monkeypatch,
                                                                       methods) -> None:
    monkeypatch.setattr(process_runner.mp, "get_all_start_methods", lambda: methods)
    runner = ProcessRunner(Session("blackjack", hp=QLearning.hyperparameters(episodes=50), seed=0))
    try:
        assert runner.start() and runner.wait_idle(DEADLINE), why(runner)
        assert runner.session.trainer.episodes == 50, why(runner)
        assert runner._child is not None and runner._child.process._start_method == methods[0]
    finally:
        runner.close()
