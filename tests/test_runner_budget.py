"""Raising the episode budget after a run continues that run, epsilon schedule included;
a used-up budget stops `n` and `.` as it stops space."""

from __future__ import annotations

import pytest

from tui_gym.algorithms import QLearning
from tui_gym.core.engine.trainer import continue_run
from tui_gym.session.runners import make_runner
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.train_view import TrainView

from .waiting import send_key, wait_for

DEADLINE = 20.0


def test_a_raised_budget_keeps_the_decay_where_it_was() -> None:
    done = QLearning.hyperparameters(episodes=1000, epsilon_decay_fraction=0.5)  # decays over 500
    hp, note = continue_run(done, done.replace(episodes=4000), 1000)
    assert hp.episodes == 4000 and hp.epsilon_decay_fraction == 0.125
    assert hp.epsilon_at(1000) == done.epsilon_at(1000) == done.epsilon_final
    assert note is not None and "goes on from episode 1,000" in note


def test_a_raised_budget_mid_decay_carries_epsilon_on_smoothly() -> None:
    hp0 = QLearning.hyperparameters(episodes=1000, epsilon_decay_fraction=0.5)
    hp, _ = continue_run(hp0, hp0.replace(episodes=2000), 200)
    for episode in (200, 300, 499, 500, 1500):
        assert abs(hp.epsilon_at(episode) - hp0.epsilon_at(episode)) < 1e-12


def test_settings_that_send_epsilon_back_up_say_so() -> None:
    hp0 = QLearning.hyperparameters(episodes=1000, epsilon_decay_fraction=0.5)
    wanted = hp0.replace(episodes=4000, epsilon_decay_fraction=0.9)  # asked for: kept
    hp, note = continue_run(hp0, wanted, 1000)
    assert hp == wanted
    assert note is not None and note.startswith("Exploration restarts")
    assert f"{hp.epsilon_at(1000):.3g}" in note


def test_nothing_to_continue_before_the_first_episode_or_when_nothing_changes() -> None:
    hp0 = QLearning.hyperparameters(episodes=1000)
    assert continue_run(hp0, hp0.replace(episodes=5000), 0) == (hp0.replace(episodes=5000), None)
    assert continue_run(hp0, hp0, 700) == (hp0, None)
    assert continue_run(hp0, hp0.replace(episodes=800), 700) == (hp0.replace(episodes=800), None)


async def test_raising_the_budget_after_a_finished_run_continues_it_in_the_app() -> None:
    hp = QLearning.hyperparameters(episodes=100, epsilon_decay_fraction=0.5)
    app = TuiGymApp(Session("blackjack", seed=0, hp=hp))
    notes: list[str] = []
    app.notify = lambda message, **kw: notes.append(message)  # type: ignore[method-assign]
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("t", "space")
        await wait_for(pilot, lambda: app.runner.finished and not app.runner.running, "100")
        final = app.session.agent.epsilon
        assert final == hp.epsilon_final
        form = app.query_one(TrainView).form
        form.input("episodes").value = "400"
        await pilot.press("space")
        assert any("goes on from episode 100" in note for note in notes), notes
        assert form.input("epsilon_decay_fraction").value == "0.125"
        await wait_for(pilot, lambda: app.runner.finished and not app.runner.running, "400")
        assert app.session.trainer.episodes == 400
        assert app.session.agent.epsilon == final
        # The curve (rolling means of epsilon) never rises: exploration did not restart.
        epsilons = app.runner.latest.series["epsilon"]
        assert all(b <= a + 1e-12 for a, b in zip(epsilons, epsilons[1:], strict=False))


@pytest.mark.parametrize("kind", ["thread", "process"])
def test_a_used_up_budget_refuses_a_step_and_an_episode_as_it_refuses_a_start(kind: str) -> None:
    session = Session("blackjack", seed=0, hp={"episodes": 30})
    session.trainer.run(episodes=30)
    runner = make_runner(session, kind)
    try:
        assert not runner.start() and runner.finished
        runner.finished = False
        assert not runner.run_one_step() and runner.finished
        runner.finished = False
        assert not runner.run_one_episode() and runner.finished
        assert runner.wait_idle(DEADLINE)
        assert session.trainer.episodes == 30 and not runner.busy
    finally:
        runner.close()


async def test_n_and_dot_say_the_budget_is_used_up_in_the_app() -> None:
    hp = QLearning.hyperparameters(episodes=20)
    session = Session("blackjack", seed=0, hp=hp)
    session.trainer.run(episodes=20)
    app = TuiGymApp(session, runner="thread")
    notes: list[str] = []
    app.notify = lambda message, **kw: notes.append(message)  # type: ignore[method-assign]
    async with app.run_test(size=(120, 40)) as pilot:
        for key in ("t", "n", "full_stop"):  # typed at once: n and . before the view mounts
            send_key(pilot, key)
        await wait_for(pilot, lambda: sum("budget is used up" in note for note in notes) == 2,
                       "the budget notice for n and for .")
        assert app.session.trainer.episodes == 20 and app.runner.latest.episodes == 20
