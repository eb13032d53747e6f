"""Numbers that agree, through the app as a person drives it.

The Train view's badge follows what happened (finished only when a budget was
used up; paused, not ready, once training has begun); the advice (`i`) and the
scoreboard read the same agent after it trained (one app drives both in
turn); a loaded agent's figures with nothing behind them read "–" (the Train
view mounted alone). Training runs on the runner's thread or headless on the
session; every wait polls a condition.
"""

from __future__ import annotations

from tui_gym.algorithms import QLearning
from tui_gym.games import game_for
from tui_gym.games.words import signed
from tui_gym.session.session import Session, default_settings
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.widgets.scoreboard import Scoreboard

from .hosts import TrainHost
from .waiting import open_train, wait_for

DEADLINE = 20.0


def badge(app: TuiGymApp | TrainHost) -> str:
    return app.train_view.stats.plain.split("  ")[0]


async def settled(pilot, app: TuiGymApp, shown: str) -> None:
    """Wait until no training runs, the view shows the runner's last snapshot, and
    the badge says `shown` (a wrong badge fails here, after the deadline)."""
    await wait_for(pilot, lambda: not app.runner.running and app.runner.wait_idle(0),
                   "the runner to go idle")
    await wait_for(pilot, lambda: app.train_view._version == app.runner.latest.version,
                   "the view to catch up")
    await wait_for(pilot, lambda: badge(app) == shown, f"the badge to say {shown!r}")


async def test_the_badge_follows_the_run_then_advice_and_scoreboard_read_the_trained_agent(
) -> None:
    hp = default_settings(game_for("gridworld"), "q-learning").replace(episodes=40)
    app = TuiGymApp(Session("gridworld", seed=0, hp=hp))
    async with app.run_test(size=(80, 24)) as pilot:
        await open_train(pilot)
        assert badge(app) == "○ ready"
        await pilot.press("space")
        await settled(pilot, app, "✓ finished")
        assert app.runner.latest.episodes == 40

        await pilot.press("x", "y")  # a fresh agent (yes: it has trained): nothing is finished
        await settled(pilot, app, "○ ready")
        assert app.runner.latest.episodes == 0

        await pilot.press("full_stop")  # one episode of a 40-episode budget
        await wait_for(pilot, lambda: app.runner.latest.episodes == 1, "one episode")
        await settled(pilot, app, "‖ paused")

        await pilot.press("x", "y")
        await settled(pilot, app, "○ ready")
        # Animated (slow), single steps: the pause lands before an episode ends, however
        # short the first one is and however busy the machine.
        await pilot.press("minus", "minus", "minus")
        await pilot.press("space")
        await wait_for(pilot, lambda: app.runner.latest.steps >= 2, "a few moves")
        await pilot.press("space")
        await settled(pilot, app, "‖ paused")  # paused before the first episode ended
        assert app.runner.latest.episodes == 0

        # The advice and the scoreboard, on a fresh agent (no episode yet: no question).
        await pilot.press("x")
        assert app.session.trainer.episodes == 0 and app.runner.latest.steps == 0
        await pilot.press("p", "i")
        view = app.play_view
        detail = str(view.query_one("#play-detail").render())
        assert "agent: has never seen this state" in detail

        await open_train(pilot)  # shown: the Play view, shown again after, reads afresh
        session = app.session
        session.trainer.run(episodes=4000)  # headless, as the runner would
        await pilot.press("p")
        await wait_for(pilot, lambda: "never seen" not in str(view.query_one("#play-detail")
                                                                .render()), "fresh advice")

        observation = view.game.last.observation
        key = session.keyer.key(observation)
        q = session.agent.values([key])[0]
        names = session.game.action_names
        values = ", ".join(f"{names[a]} {signed(float(v), 3)}" for a, v in enumerate(q))
        detail = str(view.query_one("#play-detail").render())
        assert f"(Q {values})" in detail  # the advice reads the trained table
        await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's exact figures")
        figures = session.agent_figures()
        assert view.agent_figures == figures  # ... and so does the scoreboard
        board = view.query_one(Scoreboard).text(compact=False)
        assert f"{figures['steps_over_optimal']:.2f} steps over optimal" in board


async def test_a_loaded_agent_shows_dashes_where_there_is_no_data(tmp_path) -> None:
    trained = Session("blackjack", seed=0, hp=QLearning.hyperparameters(episodes=50_000))
    trained.trainer.run(episodes=5000)
    path = trained.save(tmp_path / "bj.tgym")
    app = TrainHost(Session.load(path))  # what the Train view shows of it
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        stats = app.train_view.stats.plain.splitlines()
        assert "episodes 5,000" in stats and "steps " + f"{trained.trainer.steps:,}" in stats
        for name in ("eps/s", "time", "return", "length", "|TD|"):
            assert f"{name} –" in stats, name
        charts = app.train_view.charts
        assert all(charts.value_text(key) == "–" for key in ("return", "length", "td_error"))
        assert badge(app) == "‖ paused"  # 5,000 of 50,000 episodes: not ready, not finished
        exact = trained.reference().figures["exact_value"]
        assert f"exact value {exact:+.4f}" in stats
