"""Nothing is lost by a game switch, and a trained agent is reset only when asked.

Each game keeps its own session for the run: switching away and back (by `b`
/ `g`, the side panel's picker or the command palette) finds the agent, its
settings, its wrappers, its curves and the person's own play as they were,
with either runner. Resetting an agent that has trained (`x`, the Reset
button, or a wrapper change that gives observations a new meaning) asks first;
an untrained agent resets without a question.
"""

from __future__ import annotations

from textual.command import CommandList
from textual.widgets import Checkbox, Input

from tui_gym.algorithms import QLearning
from tui_gym.session.session import Session, default_settings
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.confirm_screen import ConfirmScreen

from .waiting import DEADLINE, send_key, wait_for, wait_until


def blackjack(episodes: int = 300, runner: str = "thread") -> TuiGymApp:
    return TuiGymApp(Session("blackjack", hp=QLearning.hyperparameters(episodes=episodes), seed=0),
                     runner=runner)


def palette_first(app: TuiGymApp) -> str:
    """The first command the open command palette lists ("" while it lists none)."""
    lists = app.screen.query(CommandList)
    if not lists or not lists.first().option_count:
        return ""
    return str(lists.first().get_option_at_index(0).prompt)


async def train_to_the_end(pilot) -> None:
    app = pilot.app
    await pilot.press("space")
    await wait_for(pilot, lambda: app.runner.finished and not app.runner.running,
                   "the budget to finish")
    assert app.runner.wait_idle(DEADLINE)


async def tick(pilot, wrapper: str) -> None:
    pilot.app.query_one(f"#wrapper-{wrapper}").query_one(Checkbox).value = True
    await pilot.pause()


async def test_each_game_keeps_its_agent_settings_wrappers_curves_and_play():
    app = blackjack()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("t")
        await train_to_the_end(pilot)
        blackjack_session = app.session
        agent, table = app.session.agent, app.session.agent.table()[0].copy()
        # Settings: a learning rate typed into the form, and a reward wrapper.
        await pilot.press("e")
        rate = app.train_view.form.input("learning_rate")
        await wait_for(pilot, lambda: app.focused is rate, "the form")
        await pilot.press(*"0.05", "enter")
        assert app.session.hp.learning_rate == 0.05
        await tick(pilot, "ScaleReward")
        assert [c.name for c in app.session.choices] == ["ScaleReward"]
        assert app.session.agent is agent  # a reward wrapper keeps the agent
        curve = app.train_view.charts.data("return")
        assert curve
        await pilot.press("p", "s")  # a hand of the person's own (with the wrapper)
        assert app.play_view.game.tally.episodes == 1
        await pilot.press("t")

        await pilot.press("g")
        assert app.session.game.name == "gridworld"
        assert app.session.trainer.episodes == 0 and not app.session.choices
        assert app.session.hp == default_settings(app.session.game, "q-learning",
                                                  app.session.env_kwargs)
        assert not app.train_view.charts.data("return")
        assert any("a new agent" in n.message for n in app._notifications)
        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "a GridWorld episode")
        assert app.runner.wait_idle(DEADLINE)

        await pilot.press("b")
        assert app.session is blackjack_session and app.session.agent is agent
        assert (app.session.agent.table()[0] == table).all()
        assert app.session.trainer.episodes == 300 and app.runner.latest.episodes == 300
        assert app.session.hp.learning_rate == 0.05
        assert app.train_view.form.input("learning_rate").value == "0.05"
        assert [c.name for c in app.session.choices] == ["ScaleReward"]
        assert app.query_one("#wrapper-ScaleReward").query_one(Checkbox).value
        assert app.train_view.charts.data("return") == curve
        assert "episodes 300\n" in app.train_view.stats.plain
        assert any("your agent (300 episodes)" in n.message for n in app._notifications)

        # The picker switches the same way, and GridWorld kept its one episode.
        await pilot.click("#game-gridworld")
        assert app.session.game.name == "gridworld" and app.session.trainer.episodes == 1
        # So does the command palette.
        await pilot.press("ctrl+p")
        await pilot.pause()
        await pilot.press(*"Blackj")
        await wait_for(pilot, lambda: palette_first(app).startswith("Game: Blackjack"),
                       "the palette to list the game")
        await pilot.press("down", "enter")
        await wait_for(pilot, lambda: app.session is blackjack_session, "the palette's switch")
        # The person's own play came back too.
        await pilot.press("p")
        assert app.play_view.game.tally.episodes == 1
        assert "Hands 1" in str(app.play_view.query_one("#play-tally").render())


async def test_the_child_process_trains_the_restored_agent():
    session = Session("blackjack", hp=QLearning.hyperparameters(episodes=1_000_000), seed=0,
                      engine="env")  # slow enough to be mid-run at the switch
    app = TuiGymApp(session, runner="process")
    async with app.run_test(size=(80, 24)) as pilot:
        # While the child trains, keys go without the pilot's wait for an idle process.
        await pilot.press("t")
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.latest.episodes > 500, "some training")
        agent = session.agent
        send_key(pilot, "g")  # while the child trains: it pauses and hands back
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "the switch")
        assert not app.runner.running
        trained = session.trainer.episodes
        assert trained > 500 and agent.episode == trained  # every episode came back
        assert any("Training paused" in n.message for n in app._notifications)
        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "a GridWorld episode")
        assert app.runner.wait_idle(DEADLINE)
        await pilot.press("b")
        assert app.session is session and app.runner.latest.episodes == trained
        # The child trains the restored agent on from where it stopped.
        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == trained + 1,
                       "one more Blackjack episode")
        assert app.runner.wait_idle(DEADLINE)
        assert app.session.agent is agent and agent.episode == trained + 1


async def test_resetting_a_trained_agent_asks_first():
    app = blackjack()
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("t")
        untrained = app.session.agent
        await pilot.press("x")  # nothing to lose yet: it resets at once
        assert not isinstance(app.screen, ConfirmScreen)
        assert app.session.agent is not untrained
        await tick(pilot, "FlattenObservation")  # untrained: applied without a question
        assert not isinstance(app.screen, ConfirmScreen)
        assert [c.name for c in app.session.choices] == ["FlattenObservation"]
        app.query_one("#wrapper-FlattenObservation").query_one(Checkbox).value = False
        await pilot.pause()
        await pilot.press("escape")  # back to the view from the panel
        await train_to_the_end(pilot)
        agent = app.session.agent

        await pilot.press("x")
        assert isinstance(app.screen, ConfirmScreen)
        assert "300 episodes" in str(app.screen.query_one("#confirm-detail").render())
        await pilot.press("escape")
        assert not isinstance(app.screen, ConfirmScreen)
        assert app.session.agent is agent and app.runner.latest.episodes == 300
        await pilot.press("x", "enter")  # the focus starts on Cancel
        assert app.session.agent is agent
        await pilot.click("#btn-reset")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("n")
        assert app.session.agent is agent

        # A wrapper change that keeps the agent does not ask; one that resets it does.
        await tick(pilot, "TimeLimit")
        assert not isinstance(app.screen, ConfirmScreen) and app.session.agent is agent
        await tick(pilot, "FlattenObservation")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("escape")
        assert app.session.agent is agent
        assert [c.name for c in app.session.choices] == ["TimeLimit"]
        assert not app.query_one("#wrapper-FlattenObservation").query_one(Checkbox).value
        assert any("Not applied" in n.message for n in app._notifications)
        await tick(pilot, "FlattenObservation")
        await pilot.press("y")
        assert [c.name for c in app.session.choices] == ["TimeLimit", "FlattenObservation"]
        assert app.session.agent is not agent and app.runner.latest.episodes == 0

        # So does an environment argument that changes the states.
        await pilot.press("g", "t", "full_stop")
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "a GridWorld episode")
        assert app.runner.wait_idle(DEADLINE)
        size = app.query_one("#env-params").query_one(Input)
        size.focus()
        size.value = "6"
        await pilot.press("enter")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("y")
        assert app.session.env_kwargs["size"] == 6 and app.session.trainer.episodes == 0
