"""The app and the learners: the algorithm picker, the generated form, live knobs, and
the step-by-step panel, checked against updates computed here by hand.

Each hand-computed example fills the learner's tables with known values,
takes one step with `n`, and works out the target from the book's formula
and the transition the panel reports; the panel must print those numbers.
"""

from __future__ import annotations

import numpy as np
from textual.widgets import Input, RadioButton, Select

from tui_gym.algorithms import ALGORITHMS, Predictor
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.confirm_screen import ConfirmScreen
from tui_gym.ui.widgets.step_panel import _num

from .waiting import open_train, send_key, wait_for, wait_until

KNOWN = {"learning_rate": 0.5, "learning_rate_schedule": "constant", "discount": 0.9,
         "epsilon_start": 0.3, "epsilon_final": 0.3}


def _known_tables(agent) -> None:
    """Distinct, easy values: Q(s, a) = 0.01 s + 0.1 a (Double Q: B is A minus 0.05)."""
    for spec in agent.tables:
        table = getattr(agent, spec.name)
        if table.dtype.kind != "f" or spec.name.startswith("model"):
            continue
        rows, cols = table.shape
        values = 0.01 * np.arange(rows)[:, None] + 0.1 * np.arange(cols)[None, :]
        table[:] = values - (0.05 if spec.name == "q_b" else 0.0)


def _hand_target(name: str, agent, record) -> float:
    """The target by the book, from the tables before the step (`_known_tables`)."""
    s2, r, gamma = record.next_state, record.reward, 0.9
    q = 0.01 * s2 + 0.1 * np.arange(agent.n_actions)
    if record.terminated:
        return r
    if name in ("q-learning", "dyna-q", "q-lambda", "dyna-q-plus", "prioritized-sweeping"):
        return r + gamma * q.max()
    if name in ("sarsa", "sarsa-lambda"):
        return r + gamma * q[record.target_action]
    if name == "expected-sarsa":
        eps = 0.3
        probs = np.full(len(q), eps / len(q))
        probs[q == q.max()] += (1 - eps) / (q == q.max()).sum()
        return r + gamma * float(probs @ q)
    if name == "double-q":  # the other table judges the updated table's best action
        other = q - 0.05 if record.table == "A" else q
        return r + gamma * other[int(np.argmax(q if record.table == "A" else q - 0.05))]
    raise AssertionError(name)


async def test_each_algorithm_explains_a_hand_computed_step() -> None:
    app = TuiGymApp(Session("gridworld", {"size": 3}, seed=0, hp=KNOWN))
    # The smallest window: the panel's numbers do not depend on its size, and there is
    # less to lay out each time the form rebuilds for another algorithm.
    async with app.run_test(size=(80, 24)) as pilot:
        view = await open_train(pilot)
        # The control learners: a prediction learner's records are checked by hand in
        # tests/test_prediction.py.
        for cls in (c for c in ALGORITHMS if not issubclass(c, Predictor)):
            if cls.name != app.session.algorithm:
                # Picked through the side panel's radio button as a click does; the
                # clicks themselves are checked below.
                app.query_one(f"#algorithm-{cls.name}", RadioButton).value = True
                await wait_for(pilot, lambda c=cls: app.session.algorithm == c.name,
                               f"the switch to {cls.name}")
                app.session.set_hyperparameters(KNOWN)
                view.form.load(app.session.hp)
            agent = app.session.agent
            _known_tables(agent)
            before = app.session.trainer.steps
            await pilot.press("n")
            await wait_for(pilot, lambda b=before: app.session.trainer.steps == b + 1,
                           f"one {cls.name} step")
            await wait_for(pilot, lambda c=cls: view.step_panel.lines
                           and view.step_panel.lines[0][1].startswith(c.title),
                           f"the {cls.name} step panel")
            record = app.runner.last_event.last_update
            text = "\n".join(body for _, body in view.step_panel.lines)
            assert app.runner.speed.animated
            if cls.name in ("monte-carlo", "n-step-sarsa") and record.target is None:
                assert "nothing is updated before then" in text
                continue
            target = record.reward if cls.name == "monte-carlo" else _hand_target(
                cls.name, agent, record)
            assert abs(record.target - target) < 1e-12, cls.name
            before_q = 0.01 * record.state + 0.1 * record.action
            before_q -= 0.05 if record.table == "B" else 0.0
            after = before_q + 0.5 * (target - before_q)
            assert f"= {_num(target)}" in text, (cls.name, text)
            assert f"{_num(before_q)} → {_num(after)}" in text, (cls.name, text)
            assert f"= {_num(target - before_q)}" in text  # the TD error
            if cls.name == "dyna-q":
                assert f"then {app.session.hp.planning_steps} simulated updates" in text
            assert view.heatmap.step_cell is not None  # the state's cell is marked


async def test_epsilon_changes_live_then_the_form_follows_the_algorithm() -> None:
    """One app training in a child process, in turn: epsilon and the learning rate
    change while it trains; the form follows the algorithm, and a trained agent asks
    before another algorithm replaces it."""
    app = TuiGymApp(Session("blackjack", seed=0, hp={"episodes": 100_000_000}), runner="process")
    async with app.run_test(size=(120, 40)) as pilot:
        view = await open_train(pilot)
        # While it trains, keys go without the pilot's wait for an idle process.
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.latest.episodes > 200, "training")
        send_key(pilot, "e")
        await wait_until(pilot, lambda: app.focused is not None
                         and view.form in app.focused.ancestors, "the form's first field")
        for name, value in (("epsilon_start", "0.2"), ("epsilon_final", "0.2"),
                            ("learning_rate", "0.05")):
            view.form.input(name).value = value
        view.form.input("learning_rate").focus()
        send_key(pilot, "enter")
        await wait_until(pilot, lambda: app.session.agent.epsilon == 0.2, "epsilon in force")
        assert app.runner.running and app.session.agent.hp.learning_rate == 0.05
        # The curve shows it once its last point is made of episodes after the change (a
        # point spans more episodes the longer the run: no fixed count of episodes will do).
        await wait_until(pilot, lambda: app.runner.latest.series["epsilon"][-1] < 0.25,
                         "the epsilon curve at the new value")

        # The form follows the algorithm, and a trained agent asks before a switch.
        send_key(pilot, "space")  # pause
        await wait_for(pilot, lambda: not app.runner.running and app.runner.wait_idle(0),
                       "the agent handed back")
        await pilot.press("x", "y")  # a fresh agent: it has trained, so it asks first
        await wait_for(pilot, lambda: app.session.trainer.episodes == 0, "the reset")
        assert isinstance(view.form.control("learning_rate_schedule"), Select)
        await pilot.click("#algorithm-dyna-q")  # untrained: no question
        await wait_for(pilot, lambda: app.session.algorithm == "dyna-q", "Dyna-Q")
        await wait_for(pilot, lambda: bool(view.form.query("#hp-planning_steps")),
                       "the planning field")
        assert isinstance(view.form.control("planning_steps"), Input)
        assert view.form.input("episodes").value == "700000"  # Dyna-Q's default here
        view.form.input("episodes").value = "2000"
        await pilot.press("escape", "space")  # back to the view; applies the form and trains
        await wait_for(pilot, lambda: app.runner.finished and not app.runner.running, "a run")
        await pilot.click("#algorithm-monte-carlo")
        await wait_for(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        await pilot.press("escape")  # no: the trained agent stays
        await wait_for(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "no")
        assert app.session.algorithm == "dyna-q" and app.session.trainer.episodes == 2_000
        assert app.query_one("#algorithm-dyna-q", RadioButton).value
        await pilot.click("#algorithm-monte-carlo")
        await wait_for(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        await pilot.click("#confirm-yes")
        await wait_for(pilot, lambda: app.session.algorithm == "monte-carlo", "the switch")
        assert app.session.trainer.episodes == 0
        await wait_for(pilot, lambda: bool(view.form.query("#hp-first_visit")), "first visit")
        assert isinstance(view.form.control("first_visit"), Select)


