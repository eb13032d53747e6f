"""The book's figures that run learners over seeds: the engine's per-episode measures they read,
the verdicts' tolerances from the run count, and each figure's claims at a few runs."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tui_gym.algorithms import algorithm
from tui_gym.cli import main
from tui_gym.core.engine.loop import FIRST_ACTION, LENGTH, ModelArrays
from tui_gym.core.engine.seeds import play_learner
from tui_gym.core.experiments.aggregate import t_quantile
from tui_gym.games import game_named
from tui_gym.session.book import figure_named
from tui_gym.session.book.figure import FigureOptions
from tui_gym.session.book.runs import (
    Played,
    above,
    below,
    counts,
    margin,
    near,
    per_time_step,
    swept,
)


def test_the_loop_records_each_episodes_first_action_and_length() -> None:
    # Max-bias: from A, left (0) leads on to B (two steps); any other action ends at once.
    model = game_named("max-bias").base_model({})
    arrays = ModelArrays.of(model)
    hp = {"epsilon_start": 1.0, "epsilon_final": 1.0, "episodes": 400}
    firsts, _ = play_learner(algorithm("q-learning")(12, hp, n_states=4, seed=3), arrays, 400,
                             column=FIRST_ACTION)
    lengths, _ = play_learner(algorithm("q-learning")(12, hp, n_states=4, seed=3), arrays,
                              400, column=LENGTH)
    assert set(np.unique(firsts).tolist()) == set(range(12))
    assert ((lengths == 2) == (firsts == 0)).all() and set(lengths.tolist()) == {1.0, 2.0}


def test_the_loop_draws_a_rewards_noise_around_its_mean() -> None:
    # Max-bias: every action from B ends with a reward drawn from N(-0.1, 1); right from A
    # ends at 0.
    model = game_named("max-bias").base_model({})
    hp = {"epsilon_start": 1.0, "epsilon_final": 1.0, "episodes": 20_000}
    learner = algorithm("q-learning")(12, hp, n_states=4, seed=5)
    returns, _ = play_learner(learner, ModelArrays.of(model), 20_000)
    left = returns[returns != 0.0]
    assert len(left) == pytest.approx(20_000 / 12, rel=0.1)
    assert abs(left.mean() + 0.1) < 4 / np.sqrt(len(left))
    assert left.std() == pytest.approx(1.0, abs=0.06)


def test_a_verdicts_tolerance_is_the_99_percent_interval_of_the_runs() -> None:
    samples = np.array([1.0, 2.0, 3.0, 4.0])
    half = t_quantile(0.995, 3) * samples.std(ddof=1) / 2
    assert margin(samples) == pytest.approx(half) and np.isnan(margin([5.0]))
    assert near("", 2.5 + half - 1e-9, samples).ok and not near("", 2.5 + half + 1e-6,
                                                                  samples).ok
    assert near("", 2.5 + half + 0.4, samples, slack=0.5).ok
    assert above("", "", samples + 2 * half, samples).ok
    assert not above("", "", samples + 1.4 * half, samples).ok  # within √2 · margin
    # One run gives no interval: nothing it measures is borne out.
    assert not near("", 1.0, [1.0]).ok and not above("", "", [2.0], [1.0]).ok
    # A claim about the lower one ("TD ends lower than MC") shows its mean first.
    lower = below("", "", samples, samples + 2 * half)
    assert lower.ok and lower.measured == f"2.5 vs {2.5 + 2 * half:.1f}"
    assert above("", "", samples + 2 * half, samples).measured == f"{2.5 + 2 * half:.1f} vs 2.5"


def test_episodes_completed_against_time_steps() -> None:
    lengths = np.array([[3.0, 2.0, 5.0], [1.0, 1.0, 8.0]])  # ends at 3, 5, 10 and 1, 2, 10
    series = per_time_step(Played("x", lengths, None, None), points=11)
    assert series.x.tolist() == list(range(11))
    assert series.y.tolist() == [0, 0.5, 1, 1.5, 1.5, 2, 2, 2, 2, 2, 3]


def test_a_swept_parameter_is_one_point_a_learner_with_its_band() -> None:
    runs = [Played("α", np.array([[1.0, 3.0], [3.0, 5.0]]), None, None),
            Played("α", np.array([[0.0, 0.0], [2.0, 2.0]]), None, None)]
    series = swept("n = 1", [0.1, 0.2], runs, lambda values: values.mean(axis=1))
    assert series.x.tolist() == [0.1, 0.2] and series.y.tolist() == [3.0, 1.0]
    half = t_quantile(0.975, 1) * np.sqrt(2) / np.sqrt(2)  # per-run means 2, 4 and 0, 2
    assert series.hi.tolist() == pytest.approx([3.0 + half, 1.0 + half])
    assert series.lo.tolist() == pytest.approx([3.0 - half, 1.0 - half])


def test_full_gives_the_books_counts_and_flags_win() -> None:
    figure = figure_named("6.4")
    assert counts(figure, FigureOptions()) == (figure.runs, figure.episodes)
    assert counts(figure, FigureOptions(full=True)) == (figure.full_runs, figure.episodes)
    assert counts(figure, FigureOptions(runs=3, episodes=9, full=True)) == (3, 9)


def test_cliff_walking_as_json_at_five_runs(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["book", "6.4", "--runs", "5", "--seed", "11", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"schema", "figure", "title", "runs", "series", "checks"}
    assert data["figure"] == "6.4" and data["runs"] == 5
    assert [s["label"] for s in data["series"]] == ["Sarsa", "Q-learning"]
    for series in data["series"]:
        assert set(series) == {"label", "x", "y", "lo", "hi"} and len(series["x"]) == 500
        assert all(lo <= y <= hi for lo, y, hi in zip(series["lo"], series["y"], series["hi"],
                                                       strict=True))
    assert all(set(c) == {"claim", "book", "measured", "ok"} and c["ok"]
               for c in data["checks"]), data["checks"]


@pytest.mark.parametrize(("name", "runs"), [("6.3", 5), ("6.5", 200), ("8.2", 10)])
def test_the_books_claims_at_a_few_runs(name: str, runs: int) -> None:
    seen: list[tuple[int, int]] = []
    result = figure_named(name).run(FigureOptions(runs=runs, seed=100),
                                    lambda done, total, _: seen.append((done, total)))
    assert result.runs == runs and result.checks
    assert result.ok, [c for c in result.checks if not c.ok]
    if name == "6.5":  # the learners take A's two actions only: ε-greedy goes left ε/2
        assert "5%" in [c.book for c in result.checks]
    assert seen and seen[-1][0] == seen[-1][1]
    for series in result.series:
        assert series.lo is not None and series.hi is not None
        assert (series.lo <= series.y + 1e-9).all() and (series.y <= series.hi + 1e-9).all()


def test_a_claim_the_runs_do_not_bear_out_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    from tui_gym.session.book import dyna

    # Without planning the maze is far from learned by episode 3.
    monkeypatch.setattr(dyna, "SETTLED", {0: 3, 5: 5, 50: 3})
    result = dyna.fig_8_2.run(FigureOptions(runs=10, seed=100), lambda *_: None)
    assert [c.ok for c in result.checks] == [True, True, False, True, True]


def test_the_full_flag_reaches_the_figure(monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    from tui_gym.cli import book_command
    from tui_gym.session.book.figure import BookFigure, FigureResult

    seen: list[FigureOptions] = []

    def run(options: FigureOptions, progress) -> FigureResult:
        seen.append(options)
        return FigureResult("9.9", "a test figure", 1)

    fake = BookFigure("9.9", "a test figure", "", "windy", run, runs=2, episodes=3)
    monkeypatch.setattr(book_command, "figure_named", lambda name: fake)
    assert main(["book", "9.9", "--full", "--seed", "4", "--json"]) == 0
    assert main(["book", "9.9", "--runs", "7", "--json"]) == 0
    capsys.readouterr()
    assert [(o.full, o.seed, o.runs) for o in seen] == [(True, 4, None), (False, 0, 7)]
