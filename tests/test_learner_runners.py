"""Every algorithm through the runners: one explained step, live knobs, the child process.

A step key takes one transition and its event carries the learner's record of
the update; hyperparameters set while training runs are in force for the next
step, in this process and in the child; the handover carries the algorithm,
and a learner of another algorithm is never taken over.
"""

from __future__ import annotations

import pickle

import pytest

from tui_gym.algorithms import ALGORITHMS, DoubleQLearning, QLearning, Sarsa
from tui_gym.session.process_runner import ProcessRunner, SessionSpec
from tui_gym.session.runner import TrainingRunner
from tui_gym.session.session import Session

from .test_runner_and_play import wait_for

DEADLINE = 20.0


@pytest.mark.parametrize("name", [cls.name for cls in ALGORITHMS])
def test_one_step_is_one_transition_explained(name: str) -> None:
    runner = TrainingRunner(Session("gridworld", {"size": 3}, seed=0, algorithm=name))
    try:
        for expected in (1, 2):
            runner.run_one_step()
            assert runner.wait_idle(DEADLINE)  # the first step may compile the rule
            assert runner.session.trainer.steps == expected
        event = runner.last_event
        record = event.last_update
        assert record is not None and record.algorithm == name
        assert record.action == event.action and record.reward == event.reward
        assert runner.session.trainer.engine == "env"
    finally:
        runner.close()


def test_hyperparameters_set_while_running_apply_at_once() -> None:
    session = Session("blackjack", seed=0, hp={"episodes": 100_000_000})
    runner = TrainingRunner(session)
    try:
        runner.start()
        assert wait_for(lambda: session.trainer.episodes > 5_000, DEADLINE)
        runner.set_hyperparameters(session.hp.replace(epsilon_start=0.2, epsilon_final=0.2,
                                                      learning_rate=0.05))
        assert session.agent.epsilon == 0.2 and session.agent.hp.learning_rate == 0.05
        # The compiled call under way ends with the old settings; the next one takes the new.
        assert wait_for(lambda: session.trainer.last.epsilon == 0.2, DEADLINE)
        seen = session.trainer.episodes
        assert wait_for(lambda: session.trainer.episodes > seen + 20_000, DEADLINE)
        assert runner.running  # nothing restarted
        assert runner.pause()
        assert session.trainer.latest.series["epsilon"][-1] == pytest.approx(0.2)
    finally:
        runner.close()


def test_the_child_takes_new_hyperparameters_and_the_algorithm() -> None:
    session = Session("blackjack", seed=0, algorithm="double-q", hp={"episodes": 100_000_000})
    runner = ProcessRunner(session)
    try:
        runner.start()
        assert wait_for(lambda: runner.latest.episodes > 20_000, DEADLINE)
        runner.set_hyperparameters({"epsilon_start": 0.3, "epsilon_final": 0.3})
        assert wait_for(lambda: runner.latest.epsilon == 0.3, DEADLINE)
        seen = runner.latest.episodes
        assert wait_for(lambda: runner.latest.episodes > seen + 20_000, DEADLINE)
        assert runner.latest.series["epsilon"][-1] == pytest.approx(0.3)
        runner.pause(wait=True)
        agent = runner.session.agent
        assert isinstance(agent, DoubleQLearning) and agent.epsilon == 0.3
        assert agent.counts_a.sum() > 0 and agent.counts_b.sum() > 0  # trained in the child
        runner.run_one_step()
        assert wait_for(lambda: runner.last_event is not None and not runner.busy, DEADLINE)
        assert runner.last_event.last_update.table in ("A", "B")
    finally:
        runner.close()


def test_the_handover_carries_the_algorithm_and_refuses_another() -> None:
    session = Session("blackjack", seed=0, algorithm="sarsa")
    assert SessionSpec.of(session).algorithm == "sarsa"
    copy = pickle.loads(pickle.dumps(session.agent))
    assert isinstance(copy, Sarsa)
    with pytest.raises(ValueError, match="sarsa"):
        QLearning(2, n_states=704).assign_from(copy)


@pytest.mark.parametrize("kind", ["thread", "process"])
def test_a_burst_of_steps_takes_every_one(kind: str) -> None:
    """Steps asked for while one is under way follow it, one transition each (a burst of
    `n` lost all but the first while the first step of a new session was slow)."""
    session = Session("cliffwalking", seed=0)
    runner = (TrainingRunner if kind == "thread" else ProcessRunner)(session)
    try:
        for _ in range(5):
            assert runner.run_one_step()
        assert wait_for(lambda: not runner.busy, DEADLINE)
        assert runner.session.trainer.steps == 5
        assert runner.last_event is not None and runner.last_event.last_update is not None
    finally:
        runner.close()
