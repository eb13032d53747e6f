"""Planning on the games: every game with a model plans, `tui-gym plan` and its JSON, the
start policies, and the runner the Plan view steps on its own thread."""

from __future__ import annotations

import json
import time
from collections.abc import Callable

import numpy as np
import pytest

from tui_gym.cli import main
from tui_gym.core.mdp import NotAvailable, solve
from tui_gym.games import GAMES, game_named
from tui_gym.games.blackjack.solver import BlackjackRules, optimal_value
from tui_gym.games.planning import PlanModel
from tui_gym.session.plan import plan
from tui_gym.session.plan import runner as plan_runner
from tui_gym.session.plan.runner import PlanRunner
from tui_gym.session.plan.start import START_POLICIES, start_policy
from tui_gym.session.session import Session

DEADLINE = 20.0


def wait_for(condition: Callable[[], bool], what: str) -> None:
    """Poll a condition the runner's thread makes true, failing after `DEADLINE` seconds."""
    deadline = time.monotonic() + DEADLINE
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.005)


@pytest.mark.parametrize("game", GAMES, ids=[g.name for g in GAMES])
def test_every_game_plans_to_its_optimum(game) -> None:
    kwargs = game.default_kwargs()
    model = game.plan_model(kwargs)
    assert isinstance(model, PlanModel) and model.model.horizon is None
    result = plan(game, kwargs, "value-iteration", theta=1e-10)
    assert result.converged
    optimum = solve(model.model, model.gamma)
    assert np.allclose(result.planner.v, optimum.v, atol=1e-5 * max(1, np.abs(optimum.v).max()))
    states = game.states.base_observations(kwargs)
    assert not isinstance(states, NotAvailable) and len(states) == model.n_base


def test_blackjack_planned_is_the_solvers_optimum() -> None:
    for rules in (BlackjackRules(), BlackjackRules(natural=True), BlackjackRules(sab=True)):
        game = game_named("blackjack")
        result = plan(game, rules.env_kwargs(), "value-iteration", theta=1e-12)
        assert result.model.start_value(result.planner.v) == pytest.approx(
            optimal_value(rules), abs=1e-9)


def test_start_policies_keep_to_the_actions_each_state_offers() -> None:
    """Example 6.7's A offers left and right only: the random policy goes left half the
    time (to B, whose actions are worth -0.1), so A is worth -0.05; the optimal and an
    agent's policies never name an action A or B does not offer."""
    game = game_named("max-bias")
    kwargs = {**game.default_kwargs(), "actions": 3}
    model = game.plan_model(kwargs)
    assert isinstance(model, PlanModel) and model.offered is not None
    result = plan(game, kwargs, "evaluate", theta=1e-12)
    assert result.planner.v[2] == pytest.approx(-0.05)  # A, as the env numbers its states
    agent_q = np.zeros((model.n_base, model.model.n_actions))
    agent_q[2, 5] = 1.0  # a table that prefers an action A does not offer
    for choice in START_POLICIES:
        policy = start_policy(model, choice, 1.0, agent_q)
        assert np.allclose(policy.sum(axis=1), 1.0)
        assert not (policy[~model.offered] > 0).any(), choice


def test_the_json_names_states_as_optimal_does(capsys) -> None:
    expected = {"ab-grid": [0, 1], "gambler": 1, "car-rental": [0, 1],
                "blackjack": [4, 2, 0]}
    for name, state in expected.items():
        assert main(["plan", name, "--method", "evaluate", "--theta", "0.01", "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        assert data["game"] == name and data["method"] == "evaluate"
        assert {"gamma", "theta", "sweeps", "iterations", "values", "policy"} <= set(data)
        assert data["values"][1]["state"] == state and data["policy"][1]["state"] == state
        game = game_named(name)
        assert set(data["policy"][1]["actions"]) == set(game.action_names)  # the random policy
    assert main(["optimal", "ab-grid", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["policy"][1]["state"] == [0, 1]


def test_figure_3_2_from_the_command_line(capsys) -> None:
    assert main(["plan", "ab-grid", "--method", "evaluate", "--theta", "1e-10", "--json"]) == 0
    values = {tuple(v["state"]): v["value"] for v in json.loads(capsys.readouterr().out)["values"]}
    assert round(values[0, 1], 1) == 8.8 and round(values[0, 3], 1) == 5.3
    assert main(["plan", "ab-grid", "--in-place", "--gamma", "0.9"]) == 0
    out = capsys.readouterr().out
    assert "24.4" in out and "Value iteration on AB grid" in out and "in-place" in out


def test_a_saved_agents_greedy_policy_starts_planning(tmp_path, capsys) -> None:
    session = Session("corner-grid", seed=0)
    session.train()
    path = session.save(tmp_path / "agent.tgym")
    assert main(["plan", "corner-grid", "--method", "evaluate", "--policy", str(path),
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["start"] == "agent" and data["converged"]
    assert data["start_value"] == pytest.approx(-2.0)  # the trained agent plays optimally
    assert main(["plan", "ab-grid", "--policy", str(path)]) == 2
    assert "holds an agent of Corner grid" in capsys.readouterr().err


@pytest.mark.parametrize("args", [["--gamma", "1.5"], ["--theta", "0"], ["--policy", "nope"],
                                  ["--method", "guess"], ["--gamma", "x"]])
def test_bad_plan_arguments_are_one_line(args, capsys) -> None:
    try:
        code = main(["plan", "corner-grid", *args])
    except SystemExit as exit_:  # argparse's own refusals
        code = exit_.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "error" in err and "Traceback" not in err


def test_the_runner_steps_runs_improves_and_follows_an_edited_world() -> None:
    game = game_named("corner-grid")
    model = game.plan_model({})
    assert isinstance(model, PlanModel)
    runner = PlanRunner(model.model, method="evaluate", theta=1e-6,
                        limited=model.limited_value)
    try:
        runner.step()
        wait_for(lambda: runner.latest.sweeps == 1, "one sweep")
        assert runner.latest.v[1] == -1.0 and not runner.latest.running
        runner.set_speed(6)  # max
        runner.run()
        wait_for(lambda: runner.latest.done and not runner.latest.running, "convergence")
        done = runner.latest
        assert round(float(done.v[1]), 3) == -14.0 and len(done.kept) == 3
        assert done.limited_value == pytest.approx(model.limited_value(done.policy))
        runner.improve()
        wait_for(lambda: runner.latest.version > done.version, "an improvement")
        assert runner.latest.changed.sum() == 14 and "14 states changed" in runner.latest.step
        # A changed world: the same states, so the values are kept and the run goes on.
        cheaper = model.model.replace(reward=model.model.reward / 2)
        before = runner.latest.sweeps
        runner.set_model(cheaper)
        wait_for(lambda: runner.latest.done and not runner.latest.running, "the new values")
        assert runner.latest.sweeps > before
        assert runner.latest.v[1] == pytest.approx(-0.5, abs=1e-4)  # greedy: one step, -1/2
        runner.restart(None)
        wait_for(lambda: runner.latest.sweeps == 0, "a restart")
        assert not runner.latest.v.any()
    finally:
        runner.close()


def test_a_run_that_never_settles_stops_and_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(plan_runner, "MAX_SWEEPS", 2_000)  # the limit's size is not the point
    model = game_named("ab-grid").plan_model({})
    assert isinstance(model, PlanModel)
    runner = PlanRunner(model.model, method="evaluate", gamma=1.0, speed=6)
    try:
        assert runner.latest.never_ending == 25  # the random policy never ends at all
        runner.set_theta(1e-30)
        runner.run()
        wait_for(lambda: not runner.latest.running and runner.latest.sweeps > 0, "the stop")
        assert "do not settle" in runner.latest.note or runner.latest.done
        assert runner.latest.sweeps == 2_000
    finally:
        runner.close()
