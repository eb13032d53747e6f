"""The Train view's prediction chart, mounted alone: the RMS curve a snapshot at a time, V
beside the true values, and why there is no figure when there is none."""

from __future__ import annotations

import asyncio

from textual.app import App, ComposeResult

from tests.hosts import TrainHost
from tui_gym.session.session import PredictionFigures, Session
from tui_gym.ui.widgets.prediction_chart import MAX_POINTS, PredictionChart


class ChartHost(App[None]):
    def compose(self) -> ComposeResult:
        yield PredictionChart(id="chart")


def figures(rms: float) -> PredictionFigures:
    return PredictionFigures(rms, (1, 2, 3), (0.1, 0.5, 0.7), (0.25, 0.5, 0.75))


def test_the_curve_grows_a_snapshot_at_a_time_and_starts_over_with_a_new_run() -> None:
    async def scenario() -> None:
        app = ChartHost()
        async with app.run_test(size=(80, 30)) as pilot:
            chart = app.query_one(PredictionChart)
            for episodes, rms in ((10, 0.4), (20, 0.3), (20, 0.25), (30, 0.2)):
                chart.show(episodes, figures(rms))
            await pilot.pause()
            assert chart.rms_points == [(10, 0.4), (20, 0.25), (30, 0.2)]
            assert "RMS error of V: 0.2000" in chart.plain
            assert "estimate V" in chart.plain and "true V^π" in chart.plain
            chart.show(5, figures(0.5))  # a fresh agent: fewer episodes
            assert chart.rms_points == [(5, 0.5)]
            for episodes in range(6, 6 + MAX_POINTS):
                chart.show(episodes, figures(0.1))
            assert len(chart.rms_points) <= MAX_POINTS
            chart.show_reason("env: TimeAwareObservation changes the observations")
            await pilot.pause()
            assert chart.plain == ("RMS error of V: n/a (env: TimeAwareObservation changes "
                                   "the observations)")
            assert chart.size.height == 1

    asyncio.run(scenario())


def test_the_train_view_shows_it_for_a_prediction_learner_only() -> None:
    async def scenario() -> None:
        session = Session("random-walk", algorithm="td0", seed=0, hp={"episodes": 40})
        app = TrainHost(session)
        async with app.run_test(size=(120, 40)) as pilot:
            view = app.train_view
            chart = view.query_one(PredictionChart)
            assert chart.display
            assert view.query_one("#train-heatmap-box").border_title == (
                "V, in every action's place")
            session.trainer.run(episodes=40)
            view.show_snapshot(session.trainer.latest, app.runner)
            await pilot.pause()
            rms = session.prediction().rms
            assert chart.rms_points[-1] == (40, rms)
            assert f"RMS error of V {rms:.4f}" in view.stats.plain
            assert "gap" not in view.stats.plain  # no greedy policy's figures
        control = TrainHost(Session("random-walk", algorithm="sarsa", seed=0))
        async with control.run_test(size=(120, 40)):
            assert not control.train_view.query_one(PredictionChart).display

    asyncio.run(scenario())
