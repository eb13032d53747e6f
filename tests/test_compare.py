"""Comparisons: seeds batched with one table each, aggregated, recorded, stopped cleanly."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from tui_gym.core.experiments import RunHistory, RunKind, RunStatus
from tui_gym.core.experiments.seed_batch import checkpoint_episodes, greedy_values
from tui_gym.core.mdp import FiniteMDP, evaluate, greedy_policy, solve
from tui_gym.session.experiments.compare import CompareProgress, CompareSpec, run_compare

from .seed_batches import cliff_model
from .seed_batches import seed_batch as _batch


@pytest.fixture(scope="module")
def cliff() -> FiniteMDP:
    return cliff_model()


@pytest.mark.parametrize("dense_states", [0, 256])
def test_greedy_values_agree_with_policy_evaluation(
    cliff: FiniteMDP, dense_states: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    from tui_gym.core.experiments import seed_batch

    monkeypatch.setattr(seed_batch, "_DENSE_STATES", dense_states)
    rng = np.random.default_rng(0)
    q = rng.integers(-3, 1, size=(4, cliff.n_states, cliff.n_actions)).astype(float)
    # Tables with no ties: their paths are walked (one that loops runs into the limit).
    q = np.concatenate([q, rng.normal(size=(4, cliff.n_states, cliff.n_actions))])
    values = greedy_values(cliff, q)
    for table, value in zip(q, values, strict=True):
        assert value == pytest.approx(evaluate(cliff, greedy_policy(table)).value)


def test_checkpoints_end_on_the_last_episode() -> None:
    assert checkpoint_episodes(500).tolist() == list(range(25, 501, 25))
    assert checkpoint_episodes(3).tolist() == [1, 2, 3]


def test_sarsa_walks_safer_than_q_learning_on_the_cliff(cliff: FiniteMDP) -> None:
    # Sutton & Barto, Example 6.6: with epsilon 0.1, SARSA's online return is above
    # Q-learning's, while Q-learning's greedy policy is the optimal one along the edge.
    hp = {"epsilon_start": 0.1, "epsilon_final": 0.1, "learning_rate": 0.5,
          "learning_rate_schedule": "constant"}
    q = _batch("q-learning", cliff, 4, 80, **hp)
    sarsa = _batch("sarsa", cliff, 4, 80, **hp)
    assert q.run() and sarsa.run()
    assert (q.done == 80).all() and not np.isnan(q.returns).any()
    last_q, last_sarsa = q.returns[:, -30:].mean(), sarsa.returns[:, -30:].mean()
    assert last_sarsa > last_q + 10
    assert q.exact is not None
    assert q.exact[:, -1].mean() == pytest.approx(solve(cliff).value)


def test_each_seed_is_its_own_learner(cliff: FiniteMDP) -> None:
    batch = _batch("q-learning", cliff, 3, 5)
    steps = np.zeros(3, dtype=np.int64)
    step = batch.steps.step

    def counted(envs: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, ...]:
        steps[envs] += 1
        return step(envs, actions)

    batch.steps.step = counted  # type: ignore[method-assign]
    batch.run()
    # Seed i's updates all land in its own rows: one per step it took.
    counts = batch.learner.counts.reshape(3, cliff.n_states, -1).sum(axis=(1, 2))
    np.testing.assert_array_equal(counts, steps)
    assert (batch.done == 5).all()


def test_a_stopped_batch_keeps_the_episodes_it_finished(cliff: FiniteMDP) -> None:
    batch = _batch("sarsa", cliff, 4, 1000)
    calls = iter(range(1_000_000))
    complete = batch.run(stop=lambda: next(calls) >= 20)
    assert not complete
    state = batch.state()
    assert (state.done < 1000).all()
    for seed in range(4):
        played = state.returns[seed, : state.done[seed]]
        assert not np.isnan(played).any()
        assert np.isnan(state.returns[seed, state.done[seed]:]).all()


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
        assert entry["exact_value"] is None  # Blackjack has no transition table
    assert not result.interrupted and seen and seen[-1].done == seen[-1].total == 240
    # One run per algorithm, kind compare, the first one's id as the group.
    assert len(records) == 2
    first = min(records, key=lambda r: r.id)
    assert result.group == first.id
    for record in records:
        assert record.summary.kind is RunKind.COMPARE
        assert record.summary.status is RunStatus.FINISHED
        assert record.summary.seeds == (5, 6, 7)
        assert {c.name for c in record.curves} == {"return", "return.lo", "return.hi"}
        assert record.summary.figure("mean_return_last") is not None
        if record.id != first.id:
            assert record.summary.group == first.id
    outcome = result.outcomes[0]
    stored = next(r for r in records if r.summary.algorithm == outcome.algorithm)
    fig = stored.summary.figure("mean_return_last")
    assert fig is not None and fig.value == pytest.approx(outcome.mean_return_last.mean)


@pytest.fixture
def quick_progress(monkeypatch: pytest.MonkeyPatch) -> None:
    from tui_gym.session.experiments import compare

    monkeypatch.setattr(compare, "PROGRESS_INTERVAL", 0.02)


@pytest.mark.usefixtures("quick_progress")
def test_stop_keeps_and_records_what_finished(tmp_path) -> None:
    spec = CompareSpec("blackjack", ["q-learning"], 2, 100_000)
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
    assert 1 <= outcome.episodes < 100_000 and outcome.seeds_done == 0
    assert record.summary.status is RunStatus.INTERRUPTED
    assert record.curve("return") is not None


def test_batches_in_child_processes_match_the_calling_thread() -> None:
    spec = CompareSpec("blackjack", ["q-learning", "sarsa"], 2, 30)
    here = run_compare(spec, processes=0)
    there = run_compare(spec, processes=2)
    for a, b in zip(here.outcomes, there.outcomes, strict=True):
        np.testing.assert_array_equal(a.curve.mean, b.curve.mean)


@pytest.mark.usefixtures("quick_progress")
def test_stop_reaches_batches_in_child_processes(tmp_path) -> None:
    spec = CompareSpec("blackjack", ["q-learning", "sarsa"], 2, 100_000)
    stop = threading.Event()

    def progress(update: CompareProgress) -> None:
        if len(update.outcomes) == 2:
            stop.set()

    with RunHistory(tmp_path / "runs.db") as history:
        result = run_compare(spec, progress=progress, stop=stop, history=history, processes=2)
        statuses = {r.status for r in history.list_runs()}
    assert result.interrupted and len(result.outcomes) == 2
    assert all(1 <= o.episodes < 100_000 for o in result.outcomes)
    assert statuses == {RunStatus.INTERRUPTED}


def test_wrappers_without_a_batched_form_play_seed_by_seed() -> None:
    from tui_gym.core.wrappers import parse_wrapper_spec

    spec = CompareSpec("blackjack", ["sarsa"], 2, 6,
                       wrappers=(parse_wrapper_spec("DelayObservation"),))
    (outcome,) = run_compare(spec, processes=0).outcomes
    assert outcome.seeds_done == 2 and len(outcome.curve) == 6
