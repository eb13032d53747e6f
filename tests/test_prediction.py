"""Prediction learners (TD(0), constant-α MC, n-step TD, TD(λ)): each update by hand, the
exact values they are scored against, their RMS error falling on the random walk, and a
session's figures. The compiled and the plain Python rules give the same runs:
tests/test_engine_plain.py."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tui_gym.algorithms import (
    TD0,
    MonteCarloPrediction,
    NStepTD,
    OfflineLambdaReturn,
    Predictor,
    TDLambda,
)
from tui_gym.algorithms.prediction import rms_curve
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.games import game_for
from tui_gym.games.base import TrainingModel
from tui_gym.session.session import Session


def walk(states: int = 5) -> TrainingModel:
    game = game_for("random-walk")
    found = game.training_model(game.normalize_kwargs({"states": states}))
    assert isinstance(found, TrainingModel)
    return found


def learner(cls: type[Predictor], states: int = 7, seed: int = 0, **hp: object) -> Predictor:
    return cls(2, hp, n_states=states, seed=seed)


# --- each update, by hand ------------------------------------------------------------------


def test_td0_moves_v_toward_r_plus_gamma_v_next() -> None:
    td = learner(TD0, learning_rate=0.1, initial_value=0.5)
    td.v[4] = 0.8
    td.learn(3, 1, 0.0, 4, False)
    assert td.v[3] == pytest.approx(0.5 + 0.1 * (0.0 + 0.8 - 0.5))
    td.learn(5, 1, 1.0, 6, True)  # the end: the target is r alone
    assert td.v[5] == pytest.approx(0.5 + 0.1 * (1.0 - 0.5))
    assert td.v[4] == 0.8 and td.visits[3] == 1


def test_monte_carlo_learns_nothing_until_the_end_then_each_return() -> None:
    mc = learner(MonteCarloPrediction, learning_rate=0.5, discount=0.9)
    mc.learn(3, 1, 0.0, 4, False)
    mc.learn(4, 1, 0.0, 5, False)
    assert not mc.v.any()
    mc.learn(5, 1, 1.0, 6, True)
    # G_2 = 1, G_1 = 0.9, G_0 = 0.81, each half-way from 0.
    assert mc.v[[3, 4, 5]] == pytest.approx([0.405, 0.45, 0.5])


def test_n_step_td_updates_the_state_of_n_steps_before_then_the_tail() -> None:
    nstep = learner(NStepTD, learning_rate=0.5, discount=0.9, n=2)
    nstep.v[5] = 1.0
    nstep.learn(3, 1, 1.0, 4, False)
    assert not nstep.v[3]  # one reward in: nothing yet
    nstep.learn(4, 1, 0.0, 5, False)  # G = 1 + 0.9·0 + 0.81·V(5) for state 3
    assert nstep.v[3] == pytest.approx(0.5 * 1.81)
    nstep.learn(5, 1, 2.0, 6, True)  # state 4: G = 0 + 0.9·2; state 5: G = 2
    assert nstep.v[4] == pytest.approx(0.5 * 1.8)
    assert nstep.v[5] == pytest.approx(1.0 + 0.5 * (2.0 - 1.0))


@pytest.mark.parametrize(("traces", "first"), [("accumulating", 0.5 * (0.45 * 0.45 + 1.0)),
                                               ("replacing", 0.5)])
def test_td_lambda_spreads_the_td_error_over_the_traces(traces: str, first: float) -> None:
    lam = learner(TDLambda, learning_rate=0.5, discount=0.9, **{"lambda": 0.5}, traces=traces)
    lam.begin_episode()
    lam.learn(1, 1, 0.0, 2, False)  # V all 0: δ = 0
    lam.learn(2, 0, 0.0, 1, False)
    lam.learn(1, 1, 1.0, 2, False)  # δ = 1; traces: e(1) = 0.45²+1 (or 1), e(2) = 0.45
    assert lam.v[1] == pytest.approx(first)
    assert lam.v[2] == pytest.approx(0.5 * 0.45)
    lam.begin_episode()  # a new episode: no trace left
    lam.learn(3, 1, 1.0, 4, True)
    assert lam.v[3] == pytest.approx(0.5) and lam.v[2] == pytest.approx(0.5 * 0.45)


def test_the_offline_lambda_return_updates_toward_lambda_returns_at_the_end() -> None:
    offline = learner(OfflineLambdaReturn, learning_rate=0.5, discount=0.9,
                      **{"lambda": 0.5})
    offline.v[3], offline.v[4] = 0.2, 0.4
    offline.learn(3, 1, 0.0, 4, False)
    assert offline.v[3] == 0.2  # nothing before the end
    offline.learn(4, 1, 1.0, 5, True)
    # G(4) = 1; G(3) = 0 + 0.9·(0.5·V(4) + 0.5·G(4)) = 0.63, with V as the episode had it.
    assert offline.v[[3, 4]] == pytest.approx([0.2 + 0.5 * (0.63 - 0.2), 0.4 + 0.5 * 0.6])


# --- the ruler -----------------------------------------------------------------------------


@pytest.mark.parametrize(("states", "values"), [(5, np.arange(1, 6) / 6),
                                                (19, np.arange(-9, 10) / 10)])
def test_the_random_policys_exact_values_are_the_books(states: int, values: np.ndarray) -> None:
    found = walk(states)
    truth = learner(TD0, states + 2).truth(found.model)
    assert truth.v[1:-1] == pytest.approx(values)
    assert truth.reached.tolist() == [False] + [True] * states + [False]  # not the ends
    assert truth.rms(truth.v) == 0.0
    assert truth.rms(truth.v + 0.25) == pytest.approx(0.25)


def test_a_predictor_following_a_greedy_policy_is_scored_against_that_policy() -> None:
    found = walk(5)
    right = learner(TD0, learning_rate=0.5)
    right.follow(np.tile([0.0, 1.0], (7, 1)), epsilon=0.0)  # always right: V = 1 everywhere
    truth = right.truth(found.model)
    assert truth.v[1:-1] == pytest.approx(np.ones(5))
    assert truth.reached.tolist() == [False, False, False, True, True, True, False]
    curve = rms_curve(right, ModelArrays.of(found.model), truth, 30)
    assert curve[-1] < 1e-3 < curve[0]
    with pytest.raises(ValueError, match="one row of 2 action values per state"):
        right.follow(np.zeros((3, 2)), epsilon=0.0)


# --- learning ------------------------------------------------------------------------------

RUNS = 20
# (learner, hyperparameters): the book's Example 6.2 settings, V starting at 0.5.
LEARNERS = [(TD0, {"learning_rate": 0.1}), (MonteCarloPrediction, {"learning_rate": 0.02}),
            (NStepTD, {"learning_rate": 0.1, "n": 2}),
            (TDLambda, {"learning_rate": 0.1, "lambda": 0.5}),
            (OfflineLambdaReturn, {"learning_rate": 0.1, "lambda": 0.5})]


@pytest.mark.parametrize(("cls", "hp"), LEARNERS, ids=[c.name for c, _ in LEARNERS])
def test_the_rms_error_falls_to_the_books_level_in_100_episodes(cls: type[Predictor],
                                                                hp: dict) -> None:
    found = walk(5)
    arrays = ModelArrays.of(found.model)
    curves = []
    for seed in range(RUNS):
        agent = learner(cls, seed=seed, initial_value=0.5, **hp)
        curves.append(rms_curve(agent, arrays, agent.truth(found.model), 100))
    mean = np.mean(curves, axis=0)
    # The first estimate (0.5 everywhere) is 0.236 off; the book's curves end near 0.05
    # (TD) to 0.1 (MC). Each run's last figure is an independent sample: the mean of RUNS
    # of them stays below 0.12 by several standard errors.
    assert mean[0] < 0.24
    assert mean[-1] < 0.12 and mean[-1] < mean[0] / 2
    assert np.std([c[-1] for c in curves]) / np.sqrt(RUNS) < 0.012


def test_a_run_cut_into_calls_is_the_same_run() -> None:
    found = walk(19)
    arrays = ModelArrays.of(found.model)
    whole, cut = (learner(NStepTD, 21, seed=4, n=3) for _ in range(2))
    truth = whole.truth(found.model)
    assert np.array_equal(np.concatenate([rms_curve(cut, arrays, truth, 7),
                                          rms_curve(cut, arrays, truth, 13)]),
                          rms_curve(whole, arrays, truth, 20))


def curves() -> dict[str, list[float]]:
    """Each learner's RMS curve, seed 3, over 15 episodes of the 19-state walk (MC's
    episodes outgrow its first buffer): tests/test_engine_plain.py compares the compiled
    rules' with the plain Python ones'."""
    found = walk(19)
    arrays = ModelArrays.of(found.model)
    out = {}
    for cls, hp in LEARNERS:
        agent = learner(cls, 21, seed=3, **hp)
        out[cls.name] = rms_curve(agent, arrays, agent.truth(found.model), 15).tolist()
    return out


# --- in a session ----------------------------------------------------------------------


def test_a_session_scores_a_predictor_on_either_loop_with_the_books_settings() -> None:
    assert Session("random-walk", algorithm="q-learning").hp.discount == 0.9  # control's
    for engine in ("model", "env"):
        session = Session("random-walk", algorithm="td0", seed=1, engine=engine,
                          hp={"episodes": 60})
        assert session.hp.discount == 1.0 and session.prediction_reason() == ""
        before = session.prediction()
        assert before is not None and before.states == (1, 2, 3, 4, 5)
        assert before.truth == pytest.approx(np.arange(1, 6) / 6)
        session.train()
        after = session.prediction()
        snap = session.prediction(session.trainer.latest)
        assert after is not None and snap is not None
        assert after.rms < before.rms / 2 and snap.rms == after.rms
    assert Session("random-walk", algorithm="sarsa").prediction() is None


def test_a_predictor_follows_a_saved_agents_policy(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    from tui_gym.cli import main

    control = Session("random-walk", algorithm="q-learning", seed=0, hp={"episodes": 300})
    control.train()
    path = control.save(tmp_path / "q.tgym")
    follower = Session("random-walk", algorithm="td0", seed=0)
    follower.follow(Session.load(path), epsilon=0.0)
    assert follower.hp.epsilon_final == 0.0 == follower.agent.epsilon
    greedy = control.agent.values(range(7)).argmax(axis=1)
    assert (follower.agent.q[:7].argmax(axis=1) == greedy).all()
    follower.train()
    figures = follower.prediction()
    assert figures is not None and figures.truth == pytest.approx([1.0] * len(figures.states))
    assert figures.rms < 0.01
    with pytest.raises(ValueError, match="SARSA is not a prediction learner"):
        Session("random-walk", algorithm="sarsa").follow(follower)
    with pytest.raises(ValueError, match=r"plays Random walk \{'states': 5\}, not Random"):
        Session("random-walk", {"states": 19}, algorithm="td0").follow(control)
    assert main(["train", "random-walk", "--algorithm", "td0", "--follow", str(path),
                 "--epsilon-final", "0.2", "--eval-episodes", "5", "--no-record",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["hyperparameters"]["epsilon_final"] == 0.2 and data["rms_error"] < 1.0
    assert main(["train", "random-walk", "--algorithm", "td0", "--follow",
                 str(tmp_path / "none.tgym"), "--no-record"]) == 2
    assert "--follow:" in capsys.readouterr().err


def test_the_step_panels_record_of_a_prediction_update() -> None:
    td = learner(TD0, learning_rate=0.5, initial_value=0.2)
    td.update_one(3, 1, 1.0, 4, False)
    record = td.last_update
    assert record is not None and record.formula == "r + γ·V(s')"
    assert (record.target, record.before, record.after, record.step_size) == pytest.approx(
        (1.2, 0.2, 0.7, 0.5))
    nstep = learner(NStepTD, n=3)
    nstep.update_one(3, 1, 0.0, 4, False)
    waiting = nstep.last_update
    assert waiting is not None and waiting.target is None and waiting.before == 0.0
    mc = learner(MonteCarloPrediction, learning_rate=0.5)
    mc.update_one(4, 1, 0.0, 5, False)
    mc.update_one(5, 1, 1.0, 6, True)
    end = mc.last_update  # the last state's own update comes first in the book's order
    assert end is not None and (end.target, end.after) == pytest.approx((1.0, 0.5))
