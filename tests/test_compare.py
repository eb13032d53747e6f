"""Comparisons: every seed its own learner (the run `train --seed` makes), aggregated,
recorded, stopped cleanly, the same in child processes; exact figures wherever the game
has a model, Blackjack included."""

from __future__ import annotations

import functools
import threading

import gymnasium as gym
import numpy as np
import pytest

from tui_gym.algorithms import algorithm
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.engine.seeds import checkpoint_episodes, greedy_values, play_learner
from tui_gym.core.experiments import RunHistory, RunKind, RunStatus
from tui_gym.core.mdp import (
    FiniteMDP,
    evaluate,
    greedy_policy,
    model_from_env,
    solve,
    with_horizon,
)
from tui_gym.session.experiments import compare
from tui_gym.session.experiments.compare import CompareProgress, CompareSpec, run_compare
from tui_gym.session.session import Session


@pytest.fixture(scope="module")
def cliff() -> FiniteMDP:
    env = gym.make("CliffWalking-v1", max_episode_steps=200)
    model = model_from_env(env)
    env.close()
    assert isinstance(model, FiniteMDP)
    return model


@pytest.mark.parametrize("dense_states", [0, 256])
def test_greedy_values_agree_with_policy_evaluation(
    cliff: FiniteMDP, dense_states: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tui_gym.core.engine import seeds

    monkeypatch.setattr(seeds, "_DENSE_STATES", dense_states)
    rng = np.random.default_rng(0)
    q = rng.integers(-3, 1, size=(4, cliff.n_states, cliff.n_actions)).astype(float)
    # Tables with no ties: their paths are walked (one that loops runs into the limit).
    q = np.concatenate([q, rng.normal(size=(4, cliff.n_states, cliff.n_actions))])
    values = greedy_values(cliff, q)
    for table, value in zip(q, values, strict=True):
        assert value == pytest.approx(evaluate(cliff, greedy_policy(table)).value)


def test_greedy_values_with_no_limit_agree_with_policy_evaluation(cliff: FiniteMDP) -> None:
    # Blackjack's hands cannot loop: every policy is valued by backward steps at once.
    # CliffWalking's can: each is valued on its own (minus infinity when it never ends).
    training = Session("blackjack").training
    assert training is not None and training.model.horizon is None
    for model in (training.model, with_horizon(cliff, None)):
        q = np.random.default_rng(1).normal(size=(3, model.n_states, model.n_actions))
        for table, value in zip(q, greedy_values(model, q), strict=True):
            assert value == pytest.approx(evaluate(model, greedy_policy(table)).value)


def test_checkpoints_end_on_the_last_episode() -> None:
    assert checkpoint_episodes(500).tolist() == list(range(25, 501, 25))
    assert checkpoint_episodes(3).tolist() == [1, 2, 3]


def test_sarsa_walks_safer_than_q_learning_on_the_cliff(cliff: FiniteMDP) -> None:
    # Sutton & Barto, Example 6.6: with epsilon 0.1, SARSA's online return is above
    # Q-learning's, while Q-learning's greedy policy is the optimal one along the edge.
    hp = {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5,
          "learning_rate_schedule": "constant", "episodes": 200}
    arrays = ModelArrays.of(cliff)
    online: dict[str, float] = {}
    for name in ("q-learning", "sarsa"):
        runs = []
        for seed in range(4):
            learner = algorithm(name)(4, hp, n_states=cliff.n_states, seed=seed)
            returns, tables = play_learner(learner, arrays, 200, [200])
            runs.append(returns[-100:].mean())
            if name == "q-learning":
                assert greedy_values(cliff, np.stack(tables))[0] == solve(cliff).value
        online[name] = float(np.mean(runs))
    assert online["sarsa"] > online["q-learning"] + 10


def test_a_seed_runs_the_same_in_a_comparison_and_in_train() -> None:
    spec = CompareSpec("frozenlake", ["expected-sarsa"], 1, 300, first_seed=7)
    (outcome,) = run_compare(spec, processes=0).outcomes
    session = Session("frozenlake", algorithm="expected-sarsa", hp={"episodes": 300}, seed=7)
    learner = algorithm("expected-sarsa")(4, session.hp, n_states=16, seed=7)
    returns, _ = play_learner(learner, session.trainer.model, 300)
    np.testing.assert_array_equal(outcome.curve.mean, returns)
    session.trainer.run(episodes=300)
    np.testing.assert_array_equal(session.agent.q, learner.q)


def test_a_stopped_job_keeps_the_episodes_it_finished() -> None:
    spec = CompareSpec("cliffwalking", ["sarsa"], 3, 1000)
    setup = compare.Setup("cliffwalking", 3, 1000, {}, (), 0)
    arms = [compare.Arm("sarsa", {}, "sarsa")]
    prepared = compare.prepare(setup, arms)
    (job,) = compare._jobs(setup, arms, prepared, [[0, 1, 2]])
    calls = iter(range(1_000_000))
    tally = compare._Tally(setup, arms, prepared)
    (job,) = tally.add([job])
    # What it reports on the way (when it runs long enough to) is taken in too.
    report = functools.partial(tally.take, job.index)
    tally.take(job.index, compare._run_job(job, lambda: next(calls) >= 5, report))
    assert spec.seeds == 3 and 0 < tally.count() < 3000 and not tally.finished(job)
    for seed in range(3):
        done = tally.done[0, seed]
        assert not np.isnan(tally.returns[0, seed, :done]).any()
        assert np.isnan(tally.returns[0, seed, done:]).all()


def test_settings_go_only_where_they_belong() -> None:
    with pytest.raises(ValueError, match="no algorithm in the comparison"):
        CompareSpec("blackjack", ["q-learning"], 2, 10, settings={"learning_rat": 0.1})
    with pytest.raises(ValueError, match="planning_steps belongs to dyna-q"):
        CompareSpec("blackjack", ["q-learning", "sarsa"], 2, 10, settings={"planning_steps": 3})
    spec = CompareSpec("blackjack", ["q-learning", "dyna-q"], 2, 10,
                       settings={"planning_steps": 3, "learning_rate": 0.2})
    result = run_compare(spec, processes=0)
    hp = {o.algorithm: o.hyperparameters for o in result.outcomes}
    assert hp["dyna-q"]["planning_steps"] == 3 and "planning_steps" not in hp["q-learning"]
    assert hp["q-learning"]["learning_rate"] == 0.2 and hp["q-learning"]["episodes"] == 10


def test_compare_output_shape_and_records(tmp_path) -> None:
    spec = CompareSpec("blackjack", ["q-learning", "sarsa"], 3, 40, first_seed=5)
    seen: list[CompareProgress] = []
    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(spec, progress=seen.append, history=history, processes=0)
        runs = history.list_runs()
        records = [history.get_run(r.id) for r in runs]
    data = result.to_json()
    assert data["game"] == "blackjack" and data["episodes"] == 40 and data["seeds"] == 3
    assert [r["algorithm"] for r in data["results"]] == ["q-learning", "sarsa"]
    for entry in data["results"]:
        assert {"hyperparameters", "mean_return_last", "ci95", "exact_value", "exact_gap",
                "curve"} <= set(entry)
        assert len(entry["curve"]) == 40
        assert set(entry["curve"][0]) == {"episode", "mean", "lo", "hi"}
        assert entry["curve"][0]["lo"] <= entry["curve"][0]["mean"] <= entry["curve"][0]["hi"]
        assert -0.5 < entry["exact_value"] < data["optimum"] < entry["exact_value"] + 0.5
        assert entry["exact_gap"] == pytest.approx(data["optimum"] - entry["exact_value"])
    assert data["optimum"] == pytest.approx(-0.046556, abs=1e-6)  # the exact optimum
    assert not result.interrupted and seen and seen[-1].done == seen[-1].total == 240
    # One run per algorithm, kind compare, the first one's id as the group.
    assert len(records) == 2
    first = min(records, key=lambda r: r.id)
    assert result.group == first.id
    for record in records:
        assert record.summary.kind is RunKind.COMPARE
        assert record.summary.status is RunStatus.FINISHED
        assert record.summary.seeds == (5, 6, 7)
        assert {c.name for c in record.curves} >= {"return", "return.lo", "return.hi",
                                                   "exact_value"}
        assert record.summary.figure("mean_return_last") is not None
        if record.id != first.id:
            assert record.summary.group == first.id
    outcome = result.outcomes[0]
    stored = next(r for r in records if r.summary.algorithm == outcome.algorithm)
    fig = stored.summary.figure("mean_return_last")
    assert fig is not None and fig.value == pytest.approx(outcome.mean_return_last.mean)


@pytest.fixture
def quick_progress(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compare, "PROGRESS_INTERVAL", 0.02)


@pytest.fixture
def spread(monkeypatch: pytest.MonkeyPatch) -> None:
    """Seeds after the first go to child processes however short the work."""
    monkeypatch.setattr(compare, "SPREAD_SECONDS", 0.0)


def test_progress_aggregates_the_outcomes_only_when_they_are_read(monkeypatch) -> None:
    """A caller that counts (a progress bar) never pays for aggregating every seed; one
    that reads `outcomes` in the callback gets them as they stand then."""
    aggregated = []
    outcomes_of = compare._Tally.outcomes
    monkeypatch.setattr(compare._Tally, "outcomes",
                        lambda self: aggregated.append(1) or outcomes_of(self))
    monkeypatch.setattr(compare, "PROGRESS_INTERVAL", 0.0)
    spec = CompareSpec("frozenlake", ["q-learning", "sarsa"], 4, 100)
    counted: list[CompareProgress] = []
    run_compare(spec, progress=counted.append, processes=0)
    assert len(counted) > 4 and len(aggregated) == 1  # the result's own
    aggregated.clear()
    read = []
    run_compare(spec, progress=lambda p: read.append((p.done, p.outcomes)), processes=0)
    assert len(aggregated) == len(read) + 1
    assert read[-1][0] == 800 and [o.seeds_done for o in read[-1][1]] == [4, 4]


@pytest.mark.usefixtures("quick_progress")
def test_stop_keeps_and_records_what_finished(tmp_path) -> None:
    spec = CompareSpec("blackjack", ["q-learning"], 1, 2_000_000)
    stop = threading.Event()

    def progress(update: CompareProgress) -> None:
        if update.outcomes:
            stop.set()

    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(spec, progress=progress, stop=stop, history=history, processes=0)
        (run,) = history.list_runs()
        record = history.get_run(run.id)
    assert result.interrupted
    (outcome,) = result.outcomes
    assert 1 <= outcome.episodes < 2_000_000 and outcome.seeds_done == 0
    assert record.summary.status is RunStatus.INTERRUPTED
    assert record.curve("return") is not None


@pytest.mark.usefixtures("spread")
def test_seeds_in_child_processes_match_the_calling_thread() -> None:
    spec = CompareSpec("blackjack", ["q-learning", "sarsa"], 3, 30)
    here = run_compare(spec, processes=0)
    there = run_compare(spec, processes=2)
    for a, b in zip(here.outcomes, there.outcomes, strict=True):
        np.testing.assert_array_equal(a.curve.mean, b.curve.mean)


@pytest.mark.usefixtures("quick_progress", "spread")
def test_stop_reaches_seeds_in_child_processes(tmp_path) -> None:
    spec = CompareSpec("taxi", ["q-learning", "sarsa"], 1, 1_000_000)
    stop = threading.Event()

    def progress(update: CompareProgress) -> None:
        if len(update.outcomes) == 2:
            stop.set()

    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(spec, progress=progress, stop=stop, history=history, processes=2)
        statuses = {r.status for r in history.list_runs()}
    assert result.interrupted and len(result.outcomes) == 2
    assert all(1 <= o.episodes < 1_000_000 for o in result.outcomes)
    assert statuses == {RunStatus.INTERRUPTED}


def test_wrappers_no_model_follows_play_seed_by_seed_on_the_env() -> None:
    from tui_gym.core.wrappers import parse_wrapper_spec

    spec = CompareSpec("blackjack", ["sarsa"], 2, 6,
                       wrappers=(parse_wrapper_spec("DelayObservation"),))
    (outcome,) = run_compare(spec, processes=0).outcomes
    assert outcome.seeds_done == 2 and len(outcome.curve) == 6


def test_prediction_learners_are_scored_by_the_rms_error_of_v(tmp_path) -> None:
    spec = CompareSpec("random-walk", ["td0", "mc-prediction", "q-learning"], 3, 60)
    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(spec, history=history, processes=0)
        records = {run.algorithm: history.get_run(run.id) for run in history.list_runs()}
    by_name = {o.algorithm: o for o in result.outcomes}
    for name in ("td0", "mc-prediction"):
        outcome = by_name[name]
        rms = []
        for seed in range(spec.first_seed, spec.first_seed + spec.seeds):  # as `train --seed`
            session = Session("random-walk", algorithm=name, seed=seed, hp={"episodes": 60})
            session.train()
            figures = session.prediction()
            assert figures is not None
            rms.append(figures.rms)
        assert outcome.rms_error == pytest.approx(np.mean(rms))
        assert outcome.rms_ci95 is not None and outcome.rms_ci95 > 0
        assert outcome.exact_value is None and outcome.exact_gap is None
        assert outcome.exact_curve is None and outcome.rms_curve is not None
        assert outcome.rms_curve.episodes[-1] == 60
        assert outcome.rms_curve.mean[-1] == pytest.approx(outcome.rms_error)
        assert outcome.rms_curve.mean[0] > outcome.rms_error  # V learned
        stored = records[name]
        figure = stored.summary.figure("rms_error")
        assert figure is not None and figure.value == pytest.approx(outcome.rms_error)
        assert stored.curve("rms_error") is not None and stored.curve("exact_value") is None
        assert outcome.to_json()["rms_error"] == pytest.approx(outcome.rms_error)
    control = by_name["q-learning"]
    assert control.rms_error is None and control.rms_curve is None
    assert control.exact_value is not None
    assert records["q-learning"].summary.figure("rms_error") is None
