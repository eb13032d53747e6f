"""The Plan view: dynamic programming on the current game's exact model, sweep by sweep."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.widgets import Button, Input, Label

from tui_gym.core.mdp import NotAvailable
from tui_gym.core.mdp.planning import check_theta
from tui_gym.games.model import freeze
from tui_gym.games.words import plural
from tui_gym.session.plan.panels import plan_panels
from tui_gym.session.plan.runner import SPEEDS, PlanRunner, PlanSnapshot
from tui_gym.session.plan.start import START_POLICIES, start_policy
from tui_gym.ui.map_editing import MapEditingView
from tui_gym.ui.widgets.heatmap_view import HeatmapView
from tui_gym.ui.widgets.map_editor import MapEditor
from tui_gym.ui.widgets.plan_status import PlanStatus
from tui_gym.ui.widgets.value_lines import ValueLines

if TYPE_CHECKING:
    from tui_gym.games.planning import PlanModel
    from tui_gym.session.session import Session

__all__ = ["PlanView"]

FRAME_SECONDS = 1 / 30  # how often the view looks for a new snapshot
METHOD_WORDS = {"evaluate": "policy evaluation", "policy-iteration": "policy iteration",
                "value-iteration": "value iteration"}
# What the keys and the buttons (`plan-COMMAND`) ask of the planner.
COMMANDS: dict[str, Callable[[PlanRunner], object]] = {
    "run": PlanRunner.toggle,
    "step": PlanRunner.step,
    "improve": PlanRunner.improve,
    "converge": lambda runner: runner.run(to_end=True),
    "in_place": lambda runner: runner.set_in_place(not runner.latest.in_place),
    "faster": lambda runner: runner.set_speed(runner.latest.speed + 1),
    "slower": lambda runner: runner.set_speed(runner.latest.speed - 1),
}


class PlanView(MapEditingView):
    """Policy evaluation, improvement, policy iteration and value iteration, watched."""

    class Published(Message):
        """The planner carried out a command (posted from its thread)."""

    SCOPED_CSS = False
    DEFAULT_CSS = """
    PlanView #plan-controls #plan-run { width: 9; }
    /* At 80x24 the row drops Improve and Converge (u and c, in the key bar) so that
       Restart and the speed fit. */
    Screen.compact PlanView #plan-improve, Screen.compact PlanView #plan-converge { display: none; }
    PlanView #plan-speed { min-width: 5; }
    PlanView #plan-knobs { height: 1; }
    PlanView #plan-knobs Label { padding: 0 1; color: $text-muted; }
    PlanView #plan-knobs Input { width: 12; height: 1; border: none; padding: 0 1; }
    PlanView #plan-knobs Input.-invalid { color: $text-error; }
    PlanView #plan-heatmap-box:focus-within { border: round $accent; }
    PlanView #plan-values, PlanView #plan-lines { display: none; }
    PlanView #plan-values.-shown, PlanView #plan-lines.-shown { display: block; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("space", "plan('run')", "Run/Pause", key_display="space"),
        Binding("n", "plan('step')", "1 step", tooltip="One sweep (or, in policy iteration, the "
                "improvement once the evaluation has converged)"),
        Binding("u", "plan('improve')", "Improve", tooltip="One greedy improvement, ties shared"),
        Binding("c", "plan('converge')", "Converge", tooltip="Run the method to its end at once"),
        Binding("1", "method('evaluate')", "Evaluate", show=False),
        Binding("2", "method('policy-iteration')", "Policy iteration", show=False),
        Binding("3", "method('value-iteration')", "Value iteration", show=False),
        Binding("o", "next_start", "Start policy"),
        Binding("r", "restart", "Restart"),
        Binding("s", "plan('in_place')", "Sync/in place"),
        Binding("plus,equals_sign", "plan('faster')", "Faster", key_display="+"),
        Binding("minus,underscore", "plan('slower')", "Slower", key_display="-"),
        Binding("e", "edit_knobs", "γ θ", tooltip="Edit the discount γ and the threshold θ"),
        Binding("d", "toggle_numbers", "Numbers", tooltip="Values as numbers / actions"),
    ]

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id)
        self.runner: PlanRunner | None = None
        self.plan: PlanModel | None = None
        self.start = "random"
        self.method = "value-iteration"
        self.numbers = False  # cells show values as numbers instead of actions
        self._key: Any = None  # (game, arguments) the runner plans for
        self._shown_version = -1
        self._reason = ""  # why there is nothing to plan on

    # --- layout --------------------------------------------------------------
    def compose(self) -> ComposeResult:
        self._run = Button("▶ Run", id="plan-run", variant="success", compact=True,
                           tooltip="Run the method at the chosen speed, or pause (space)")
        self._speed = Label(SPEEDS[3][0], id="plan-speed", classes="speed")
        self._heatmap = HeatmapView(id="plan-heatmap")
        self._values = HeatmapView(id="plan-values")
        self._lines = ValueLines(id="plan-lines")
        self._status = PlanStatus(id="plan-status")
        with Horizontal(id="plan-controls", classes="controls"):
            yield self._run
            yield Button("1 step", id="plan-step", compact=True, tooltip="One sweep (n)")
            yield Button("Improve", id="plan-improve", compact=True,
                         tooltip="One greedy improvement (u)")
            yield Button("Converge", id="plan-converge", compact=True,
                         tooltip="Run the method to its end at once (c)")
            yield Button("Restart", id="plan-restart", compact=True,
                         tooltip="Start over from the start policy, values 0 (r)")
            yield Button("−", id="plan-slower", compact=True, tooltip="Slower (-)")
            yield self._speed
            yield Button("+", id="plan-faster", compact=True, tooltip="Faster (+)")
        with Horizontal(id="plan-knobs"):
            yield Label("γ")
            yield Input("", id="plan-gamma", compact=True, tooltip="The discount, in (0, 1]")
            yield Label("θ")
            yield Input("", id="plan-theta", compact=True,
                        tooltip="Stop when the largest change is below θ; ties within θ")
        yield self._status
        with VerticalScroll(id="plan-body"):
            yield MapEditor(id="plan-editor")
            with Vertical(id="plan-heatmap-box", classes="heatmap-box"):
                yield self._heatmap
            yield self._values
            yield self._lines

    def on_mount(self) -> None:
        self.query_one("#plan-heatmap-box").border_title = "Values and the policy"
        self.set_interval(FRAME_SECONDS, self._poll)
        self.reload()
        self.call_after_refresh(self._focus_if_shown)

    def on_unmount(self) -> None:
        self._close_runner()

    def focus_default(self) -> None:
        self._heatmap.focus()

    def _focus_if_shown(self) -> None:
        """The keyboard once built, unless another view is shown by then."""
        if self.display:
            self.focus_default()

    @staticmethod
    def key_help() -> list[tuple[str, str]]:
        """(key, what it does) in this view."""
        return [
            ("1 / 2 / 3", "method: policy evaluation / policy iteration / value iteration"),
            ("space", "run the method at the chosen speed / pause"),
            ("n", "one step: a sweep (policy iteration improves once evaluation converged)"),
            ("c", "run the method to its end at once"),
            ("u", "one policy improvement: greedy on the values, ties shared"),
            ("s", "sweeps synchronous (two arrays) / in place"),
            ("+ / -", "faster / slower (1 ... 50 sweeps a second, max)"),
            ("o", "the start policy: random, the optimum, the agent's greedy policy"),
            ("r", "start over from the start policy with values 0"),
            ("e", "edit γ and θ (enter applies, esc back)"),
            ("d", "the cells show the values as numbers / the policy's actions"),
            ("m", "the map editor on a grid game: each edit plans on from the values"),
        ]

    # --- the game and its model -------------------------------------------------
    def reload(self) -> None:
        """Follow the session: a new game starts planning afresh, new arguments (an edited
        map) go on from the values the runner has."""
        session = self.session
        key = (session.game.name, freeze(session.env_kwargs))
        if key == self._key:
            return
        same_game = self._key is not None and self._key[0] == key[0]
        self._key = key
        if not same_game:
            self._close_runner()
            self.plan = None
            self.focus_target = session.game.layout.default_focus(session.env_kwargs)
            self._heatmap.show_message(f"Building {session.game.title}'s model…")
        self._build_model(session, key)
        self.follow_map()

    @work(thread=True, exclusive=True, group="plan-model")
    def _build_model(self, session: Session, key: Any) -> None:
        model = session.game.plan_model(session.env_kwargs)
        self.app.call_from_thread(self._use_model, key, model)

    def _use_model(self, key: Any, model: PlanModel | NotAvailable) -> None:
        if key != self._key:
            return  # a newer world was asked for meanwhile
        if isinstance(model, NotAvailable):
            self._close_runner()
            self.plan, self._reason = None, model.reason
            self._heatmap.show_message(f"Nothing to plan on: {model.reason}")
            self._show_lines(None)
            return
        old, self.plan, self._reason = self.plan, model, ""
        runner = self.runner
        if runner is not None and old is not None and old.n_base == model.n_base:
            runner.set_model(model.model, model.limited_value)
        else:
            self._close_runner()
            self.runner = PlanRunner(model.model, method=self.method, gamma=model.gamma,
                                     theta=1e-4, limited=model.limited_value,
                                     on_command=self._published)
            self.query_one("#plan-gamma", Input).value = f"{model.gamma:g}"
            self.query_one("#plan-theta", Input).value = "1e-04"
        self._shown_version = -1

    def _close_runner(self) -> None:
        if self.runner is not None:
            self.runner.close()
            self.runner = None

    # --- drawing -------------------------------------------------------------------
    def _published(self) -> None:
        """On the planner's thread after a command: ask for a drawing (safe from any thread)."""
        self.post_message(self.Published())

    def on_plan_view_published(self, message: Published) -> None:
        """A command's effect: drawn now, not at the next look."""
        self._poll()

    def _poll(self) -> None:
        runner = self.runner
        if runner is None or not self.display:
            return
        snapshot = runner.latest
        if snapshot.version != self._shown_version:
            self._shown_version = snapshot.version
            self.show_snapshot(snapshot)

    def show_snapshot(self, snapshot: PlanSnapshot) -> None:
        """Draw one snapshot of the planner."""
        plan, session = self.plan, self.session
        if plan is None or len(snapshot.v) != plan.model.n_states:
            return
        self.method = snapshot.method
        self._heatmap.show(plan_panels(session.game, session.env_kwargs, plan, snapshot.v,
                                       snapshot.policy, snapshot.changed, self.focus_target,
                                       self.numbers))
        run = "⏸ Pause" if snapshot.running else "▶ Run"
        if str(self._run.label) != run:
            self._run.label = run
        speed = SPEEDS[snapshot.speed][0]
        if str(self._speed.content) != speed:
            self._speed.update(speed)
        sweep = "in place" if snapshot.in_place else "synchronous"
        state = "running" if snapshot.running else "done" if snapshot.done else "paused"
        delta = "–" if math.isinf(snapshot.delta) else f"{snapshot.delta:.3g}"
        improvements = (f" · {plural(snapshot.iterations, 'improvement')}"
                        if snapshot.iterations else "")
        last = f" · {snapshot.step}" if snapshot.step else ""
        self._status.show((
            f"{METHOD_WORDS[snapshot.method]} (1 2 3) · start: {self.start} (o) · {sweep} (s)",
            f"{state} · sweep {snapshot.sweeps} · Δ {delta}{improvements}{last}",
            self._meaning(snapshot), snapshot.note or self._never_ends(snapshot),
        ))
        self._show_lines(snapshot)

    def _meaning(self, snapshot: PlanSnapshot) -> str:
        """Which value the view shows, beside the tool's own where they differ."""
        plan = self.plan
        assert plan is not None
        start = plan.start_value(snapshot.v)
        bare = " of the game without its wrappers" if self.session.applied else ""
        book = (f"values{bare}: discounted by γ = {snapshot.gamma:g}, no episode limit (the "
                f"book's); start average {start:+.4g}")
        limited = snapshot.limited_value
        if plan.horizon is None and snapshot.gamma == 1.0:
            return book + " (the tool's exact value too)"
        if limited is None:
            return book + " · the tool's exact value of the policy: when paused"
        return (f"{book} · the tool's exact value of this policy (undiscounted, "
                f"{plan.horizon}-step episodes): {limited:+.4g}")

    @staticmethod
    def _never_ends(snapshot: PlanSnapshot) -> str:
        stuck = snapshot.never_ending
        if not stuck:
            return ""
        return (f"with γ = 1 this policy can go round for ever from {plural(stuck, 'state')}: "
                "no episode ends, so their values are no episode's")

    def _show_lines(self, snapshot: PlanSnapshot | None) -> None:
        plan = self.plan
        panel = plan.value_panel if plan is not None and snapshot is not None else None
        self._values.set_class(panel is not None, "-shown")
        if snapshot is not None and panel is not None:
            self._values.show([panel(snapshot.v)])
        line = plan.line if plan is not None and snapshot is not None else None
        self._lines.set_class(line is not None, "-shown")
        if snapshot is not None and line is not None:
            curves = [(f"sweep {sweep}", values[line.states]) for sweep, values in snapshot.kept]
            if snapshot.sweeps not in {sweep for sweep, _ in snapshot.kept}:
                curves.append((f"sweep {snapshot.sweeps}", snapshot.v[line.states]))
            self._lines.show(line.x, curves, line.policy_numbers(snapshot.policy),
                             line.x_label, line.action_label)

    @on(HeatmapView.FocusChanged, "#plan-heatmap")
    def _focus_moved(self, event: HeatmapView.FocusChanged) -> None:
        event.stop()
        session = self.session
        self.focus_target = session.game.layout.focus_at(*event.cell, session.env_kwargs)
        self._redraw()

    # --- actions ---------------------------------------------------------------------
    def _command(self) -> PlanRunner | None:
        if self.runner is None:
            self.app.notify(self._reason or "The model is still being built.", timeout=3)
        return self.runner

    def action_plan(self, command: str) -> None:
        """Hand the planner one of `COMMANDS`."""
        if (runner := self._command()) is not None:
            COMMANDS[command](runner)

    def action_method(self, method: str) -> None:
        if (runner := self._command()) is not None:
            self.method = method
            runner.set_method(method)

    def action_next_start(self) -> None:
        self.start = START_POLICIES[(START_POLICIES.index(self.start) + 1) % len(START_POLICIES)]
        self.action_restart()

    def action_restart(self) -> None:
        runner, plan = self._command(), self.plan
        if runner is None or plan is None:
            return
        choice, gamma, q = self.start, runner.latest.gamma, None
        if choice == "agent":
            q = self._agent_q()
            if q is None:
                self.app.notify("The agent's table cannot be read here (wrappers hide the "
                                "states): starting from the random policy.", timeout=4)
                choice = self.start = "random"
        runner.restart(lambda: start_policy(plan, choice, gamma, q))

    def _agent_q(self) -> np.ndarray | None:
        runner = getattr(self.app, "runner", None)  # none where the Plan view runs alone
        latest = runner.latest if runner is not None else None
        return self.session.base_q(latest if latest is not None and latest.version > 0 else None)

    def action_toggle_numbers(self) -> None:
        self.numbers = not self.numbers
        self._redraw()

    def _redraw(self) -> None:
        """Draw the latest snapshot now (a change of the view's own, not the planner's)."""
        self._shown_version = -1
        self._poll()

    def action_edit_knobs(self) -> None:
        self.query_one("#plan-gamma", Input).focus()

    @on(Input.Submitted, "#plan-gamma, #plan-theta")
    def _knob_set(self, event: Input.Submitted) -> None:
        event.stop()
        runner = self._command()
        if runner is None:
            return
        field = event.input
        try:
            value = float(event.value)
            if field.id == "plan-gamma":
                if not 0.0 < value <= 1.0:
                    raise ValueError(f"γ must be in (0, 1], got {event.value!r}")
                runner.set_gamma(value)
            else:
                runner.set_theta(check_theta(value))
        except ValueError as error:
            field.add_class("-invalid")
            text = str(error) if "must" in str(error) else f"not a number: {event.value!r}"
            self.app.notify(text, severity="error", timeout=4)
            return
        field.remove_class("-invalid")

    def on_key(self, event: Any) -> None:
        if event.key == "escape" and isinstance(self.app.focused, Input):
            event.stop()
            self.focus_default()

    @on(Button.Pressed)
    def _button(self, event: Button.Pressed) -> None:
        command = (event.button.id or "").removeprefix("plan-")
        if command == "restart":
            event.stop()
            self.action_restart()
        elif command in COMMANDS:
            event.stop()
            self.action_plan(command)

    # --- the map editor ------------------------------------------------------------
    def open_editor(self) -> bool:
        """Show the map editor above the values; False when the game has no map."""
        if self.editor is None or not self.can_edit_map():
            return False
        self.call_after_refresh(self.start_editor().focus_canvas)
        return True
