"""The Train view: watch a tabular learner learn the current game, live or step by step.

The app's timer hands it the runner's latest snapshot (`show_snapshot`); its heatmaps and
exact figures are computed off the event loop (`exact_figures`).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any, ClassVar

from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import Button, Label

from tui_gym.algorithms import ALGORITHMS, Settings
from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.engine.trainer import continue_run
from tui_gym.ui.exact_figures import Figures, LatestOnly, Request, compute, key_wait_of
from tui_gym.ui.map_editing import MapEditingView
from tui_gym.ui.widgets.board_kinds import board_class
from tui_gym.ui.widgets.boards import Board
from tui_gym.ui.widgets.heatmap_view import HeatmapView
from tui_gym.ui.widgets.hyperparameter_form import HyperparameterForm
from tui_gym.ui.widgets.map_editor import MapEditor
from tui_gym.ui.widgets.prediction_chart import PredictionChart
from tui_gym.ui.widgets.progress_line import ProgressLine
from tui_gym.ui.widgets.stats_panel import StatsPanel, format_duration, run_state
from tui_gym.ui.widgets.step_panel import StepPanel, explain
from tui_gym.ui.widgets.training_charts import TrainingCharts

if TYPE_CHECKING:
    from tui_gym.session.speeds import Runner as TrainingRunner

STATE_POLL_SECONDS = 0.25  # how often the view checks for a pause with no new snapshot
NO_TRACES_SECONDS = 4.0  # how long `E` says a learner has no traces (once, for a burst)


class TrainView(MapEditingView):
    """Controls, live statistics, learning curves and Q-table heatmaps."""

    # Not scoped: the `Screen.compact ...` rules must match from the screen down.
    SCOPED_CSS = False
    DEFAULT_CSS = """
    TrainView #train-engine {
        width: 1fr; height: 1; color: $text-muted; text-style: italic;
        text-wrap: nowrap; text-overflow: ellipsis;
    }
    TrainView #train-speed { min-width: 8; }
    TrainView #train-top, TrainView #train-middle { height: auto; }
    TrainView #train-top > * { height: auto; min-height: 9; }  /* the two boxes line up */
    TrainView #train-charts { width: 1fr; }
    TrainView #train-board-box { display: none; width: 36; height: auto; margin-left: 1; }
    TrainView #train-board-box > Board { width: 100%; height: 7; }
    TrainView #train-board-caption {
        color: $text-muted; width: 100%; height: auto; min-height: 3; padding: 0 1;
    }
    TrainView #train-step { display: none; }
    TrainView #train-board-box.-shown, TrainView #train-step.-animated { display: block; }
    TrainView #train-board-box.-stepping { border-left: thick $accent; }
    TrainView #train-heatmap-box:focus-within { border: round $primary; }
    /* At 80x24 the editor takes the place of the numbers and the charts, and the form
       hides until `e` (or a bad value) asks for it. */
    Screen.compact TrainView.-mapping #train-top, Screen.compact TrainView.-mapping #train-middle,
    Screen.compact TrainView #train-speed, Screen.compact TrainView #train-engine,
    Screen.compact TrainView #train-form { display: none; }
    Screen.compact TrainView #train-top { layout: vertical; }
    Screen.compact TrainView #train-top > * { min-height: 0; }
    Screen.compact TrainView #train-controls Button { margin-right: 0; }
    Screen.compact TrainView #train-form.-editing { display: block; }
    Screen.compact TrainView #train-heatmap-box { border: none; }
    Screen.compact TrainView #train-board-box { width: 24; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("e", "edit_hyperparameters", "Edit", tooltip="Edit the hyperparameters"),
        # One key, two answers: a λ learner's toggle (in the key bar), or one line saying
        # that this learner has no traces.
        Binding("E", "toggle_traces", "Traces",
                tooltip="The heatmap: the values, or the eligibility traces of this episode"),
        Binding("E", "no_traces", show=False),
    ]

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.focus_target: Any = None  # what the heatmaps follow (a target, a slice)
        self._snapshot: TrainingSnapshot | None = None
        self._version = -1
        self._state = ""
        self._board: Board | None = None
        self._board_kind = ""
        self._scene: Any = None
        self._scene_event: Any = None
        self._layout_key: Any = None  # (game, env kwargs) the focus belongs to
        self.shows_traces = False  # the heatmap shows the traces (a λ learner's), not Q
        self._no_traces_until = 0.0  # while that is said, `E` says it no more
        # The exact figures, computed off the event loop.
        self._exact: LatestOnly[Request, Figures] = LatestOnly(self, compute)
        self._figures: Figures | None = None  # the ones shown

    # --- the app and its runner ----------------------------------------------
    @property
    def runner(self) -> TrainingRunner:
        return self.app.runner  # type: ignore[attr-defined]

    # --- layout ------------------------------------------------------------
    def compose(self) -> ComposeResult:
        session = self.session
        # The parts the view updates, kept at hand: a timer tick never has to
        # search the DOM (and cannot miss while the app shuts down).
        self._toggle = Button("▶ Start", id="btn-toggle", variant="success", compact=True,
                              tooltip="Start or pause training (space)",
                              action="app.toggle_training")
        self._episode = Button("1 episode", id="btn-episode", compact=True,
                               tooltip="Train for exactly one episode (.)",
                               action="app.one_episode")
        self._speed = Label("", id="train-speed", classes="speed")
        self.progress = ProgressLine(id="train-progress")
        self._engine = Label("", id="train-engine", markup=False)
        self.stats = StatsPanel(id="train-stats")
        self.form = HyperparameterForm(session.hp, id="train-form")
        self.charts = TrainingCharts(id="train-charts")
        self._prediction = PredictionChart(id="train-prediction")
        self._prediction.display = session.predicts
        self._board_box = Vertical(id="train-board-box")
        self._caption = Label("", id="train-board-caption")
        self._heatmap_box = Vertical(id="train-heatmap-box", classes="heatmap-box")
        self.heatmap = HeatmapView(id="train-heatmaps")
        self.step_panel = StepPanel(id="train-step")

        with Horizontal(id="train-controls", classes="controls"):
            yield self._toggle
            yield self._episode
            yield Button("Reset", id="btn-reset", variant="error", compact=True,
                         tooltip="A fresh agent: empty Q-table, fresh statistics (x)",
                         action="app.request_reset")
            yield Button("−", id="btn-slower", compact=True, tooltip="Slower (-)",
                         action="app.slower")
            yield self._speed
            yield Button("+", id="btn-faster", compact=True, tooltip="Faster (+)",
                         action="app.faster")
        yield self.progress
        yield self._engine
        with VerticalScroll(id="train-body"):
            with Horizontal(id="train-top"):
                yield self.stats
                yield self.form
            with Horizontal(id="train-middle"):
                yield self.charts
                with self._board_box:
                    yield self._caption
            yield self._prediction
            yield self.step_panel
            with self._heatmap_box:
                yield self.heatmap

    def on_mount(self) -> None:
        self.set_interval(STATE_POLL_SECONDS, self._poll_state)
        self.reload()

    # --- parts -------------------------------------------------------------
    @property
    def speed_name(self) -> str:
        return str(self._speed.content)

    # --- what the app calls ------------------------------------------------
    def reload(self) -> None:
        """Start over from the session (after a rebuild or an agent reset)."""
        session, runner = self.session, self.runner
        game = session.game
        layout_key = (game.name, tuple(sorted(session.env_kwargs.items())))
        if layout_key != self._layout_key:
            self._layout_key = layout_key
            self.focus_target = game.layout.default_focus(session.env_kwargs)
        if game.board != self._board_kind and self._board is not None:
            self._board.remove()
            self._board = None
        self._scene = self._scene_event = None
        if session.hp is not None:
            self.form.load(session.hp)
        self.charts.clear()
        self._prediction.clear()
        self._prediction.display = session.predicts
        self.shows_traces = self.shows_traces and session.learner_class.has_traces
        self.refresh_bindings()  # `E` toggles, or says there are no traces
        self._show_heatmap_title()
        self._heatmap_box.border_subtitle = (
            f"←↑↓→ / hjkl / click: {game.layout.focus_help}" if game.layout.has_focus else ""
        )
        self._version = -1
        self._state = ""
        self._exact.drop()  # figures of what was shown before never reach the screen
        self.show_speed(runner.speed.name)
        self.show_snapshot(runner.latest, runner)
        self.follow_map()

    # --- the map editor ----------------------------------------------------
    async def open_editor(self) -> bool:
        """Show the map editor with the keyboard on it; False when the game has no map."""
        if not self.can_edit_map():
            return False
        if self.editor is None:  # mounted when first opened
            await self.mount(MapEditor(id="train-editor"), before=self._heatmap_box)
        self.start_editor().focus_canvas()  # at once: the keys typed after `m` go to the map
        return True

    @property
    def shown_version(self) -> int:
        """The version of the snapshot on screen (-1: none yet)."""
        return self._version

    def show_snapshot(self, snapshot: TrainingSnapshot, runner: TrainingRunner) -> None:
        """Draw a snapshot (cheap when it is the one shown); while training runs, a new one
        waits while a key is answered (the app's timer offers it again)."""
        held = runner.running and self._version >= 0 and key_wait_of(self.app) > 0
        if snapshot.version != self._version and not held:
            self._version = snapshot.version
            self._snapshot = snapshot
            self.stats.show_snapshot(snapshot)
            self.charts.update_from(snapshot)
            self._show_progress(snapshot, runner)
            self._show_engine(snapshot)
            self._ask_figures()
        self._show_state(runner)
        self._show_board(runner)

    def show_speed(self, name: str) -> None:
        """Show the training speed's name (and the board only at animated speeds)."""
        if str(self._speed.content) != name:
            self._speed.update(name)
        self.stats.show_speed(name)
        self._show_board(self.runner)

    def read_hyperparameters(self) -> Settings | None:
        """The hyperparameters in the form, or None (with the bad fields marked and shown)."""
        hp = self.form.read()
        if hp is None:
            self.form.add_class("-editing")
            self.call_after_refresh(self.form.scroll_visible)
        return hp

    def focus_default(self) -> None:
        """Give the keyboard to the map while the editor is open, else to the heatmap (not
        scrolled to: it would hide the run's state above)."""
        if self.editing_map and (editor := self.editor) is not None:
            editor.focus_canvas()
        else:
            self.heatmap.focus(scroll_visible=False)

    def key_help(self) -> list[tuple[str, str]]:
        """The keys this view adds to the app's own training keys."""
        keys = [
            ("e", "edit the hyperparameters (enter applies, also while training runs; "
                  "esc: back, dropping an edit not applied)"),
            ("tab / shift+tab", "move between fields and buttons"),
            ("E", "the heatmap: Q (or V) / the eligibility traces e of the episode in "
                  "progress, live (the λ learners)"),
        ]
        layout = self.session.game.layout
        if layout.has_focus:
            keys.append(("←↑↓→ / hjkl / click", layout.focus_help))
        if self.engine_note:
            keys.append(("engine", self.engine_note))
        return keys

    # --- drawing pieces ----------------------------------------------------
    def _show_progress(self, snapshot: TrainingSnapshot, runner: TrainingRunner) -> None:
        rate = snapshot.episodes_per_second
        remaining = max(0, snapshot.budget - snapshot.episodes)
        eta = format_duration(remaining / rate) if runner.running and rate > 0 and remaining else ""
        self.progress.show(snapshot.episodes, snapshot.budget, eta)

    def _show_heatmap_title(self) -> None:
        predicts = self.session.predicts
        if self.shows_traces:
            title = ("e(s): the traces of this episode, in every action's place" if predicts
                     else "e(s,a): the eligibility traces of this episode")
        else:
            title = "V, in every action's place" if predicts else "Q-table"
        self._heatmap_box.border_title = title

    def _ask_figures(self) -> None:
        """Have the heatmaps and the exact figures of the snapshot shown computed off the
        event loop (`_show_figures` draws them)."""
        snapshot = self._snapshot
        if snapshot is not None:
            traces = self.shows_traces and snapshot.traces is not None
            self._exact.ask(Request(self.session.detached(), snapshot, self.focus_target,
                                    traces))

    @on(LatestOnly.Computed)
    def _computed(self, message: LatestOnly.Computed) -> None:
        message.stop()
        figures = self._exact.done(message)
        if figures is not None and self.is_attached:
            self._show_figures(figures)

    @property
    def figures_shown(self) -> bool:
        """Whether the exact figures on screen are the shown snapshot's, none to come."""
        figures = self._figures
        return (self._exact.idle and figures is not None
                and figures.request.snapshot is self._snapshot)

    def _show_figures(self, figures: Figures) -> None:
        """Draw one computation's heatmaps, exact reference and prediction figures: the
        stats panel, its note and the prediction chart all from the same snapshot."""
        self._figures = figures
        request = figures.request
        session, view = request.session, self.heatmap
        traces = self.shows_traces and request.snapshot.traces is not None
        if request.focus != self.focus_target or request.traces != traces:
            pass  # keys have moved the heatmaps on: theirs are asked for, the cursor stays
        elif figures.panels is None:
            view.focus_cell = None
            view.show_message(figures.hidden)
        else:
            layout = session.game.layout
            view.focus_cell = (layout.focus_cell(request.focus, session.env_kwargs)
                               if layout.has_focus else None)
            view.show(figures.panels)
        self.stats.show_reference(figures.reference, figures.note)
        if session.predicts:  # a prediction learner's RMS error and V against the exact values
            if figures.prediction is None:
                self._prediction.show_reason(figures.prediction_reason)
            else:
                self._prediction.show(request.snapshot.episodes, figures.prediction)

    @property
    def engine_note(self) -> str:
        """Which engine trains and why, in full (the line shows what fits)."""
        return str(self._engine.content)

    def _show_engine(self, snapshot: TrainingSnapshot) -> None:
        """Say which engine trains and why, on one line (the whole in its tooltip)."""
        reason = self.session.engine_reason
        if snapshot.status:
            reason = snapshot.status  # "compiling the learners, once"
        elif snapshot.engine == "env" and reason.startswith("model"):
            reason = "env: one step at a time while animating (the model at max speed)"
        if reason != self.engine_note:
            self._engine.update(reason)
            self._engine.tooltip = reason
            self.stats.tooltip = reason  # the compact layout hides the line

    def _show_state(self, runner: TrainingRunner) -> None:
        """The badge, from what is shown: running, finished, paused or ready."""
        snapshot = self._snapshot
        busy = runner.running or not runner.wait_idle(0)
        episodes = snapshot.episodes if snapshot is not None else 0
        steps = snapshot.steps if snapshot is not None else 0
        budget = self.session.agent.hp.episodes
        state = run_state(busy, episodes, steps, budget)
        if state == self._state:
            return
        self._state = state
        self.stats.show_state(state)
        button = self._toggle
        running = state == "running"
        button.label = "‖ Pause" if running else "▶ Start"
        button.variant = "warning" if running else "success"

    def _poll_state(self) -> None:
        if self.display and self.is_attached:
            self._show_state(self.runner)

    # --- the board at animated speeds --------------------------------------
    def _show_board(self, runner: TrainingRunner) -> None:
        box = self._board_box
        scene = runner.last_scene
        animated = runner.speed.animated and getattr(self._snapshot, "engine", "") == "env"
        shown = animated and scene is not None
        box.set_class(shown, "-shown")
        self.step_panel.set_class(runner.speed.animated, "-animated")
        if not animated or scene is None:
            self._show_step(None)
            return
        board = self._board
        if board is None:
            self._board_kind = self.session.game.board
            board = self._board = board_class(self._board_kind)(interactive=False)
            board.can_focus = False
            self._board_box.mount(board, before=0)
        event = runner.last_event
        if scene != self._scene:
            self._scene = scene
            try:
                board.show_scene(scene, reveal=True)
            except Exception as exc:  # a board that cannot draw must not stop the view
                self.log.error(f"board could not show the scene: {exc!r}")
        if event is not self._scene_event:
            self._scene_event = event
            self._caption.update(self._describe(event))
            self._show_step(event)

    def _show_step(self, event: Any) -> None:
        """Explain a step's update in the step panel, and mark its state on the heatmap."""
        record = getattr(event, "last_update", None)
        self._board_box.set_class(record is not None, "-stepping")
        if record is None:
            if self.step_panel.lines or not self.step_panel.content:
                self.step_panel.show([])
            if self.heatmap.step_cell is not None:
                self.heatmap.step_cell = None
            return
        session = self.session
        game, kwargs = session.game, session.env_kwargs
        self.step_panel.show(explain(
            event, record, game.action_names,
            lambda observation: game.states.describe(observation, kwargs),
            session.learner_class.title,
            lambda row: game.states.describe(session.keyer.observation(row), kwargs),
        ))
        found = session.heatmap_cell(event.observation, self.focus_target)
        if found is None:
            self.heatmap.step_cell = None
            return
        focus, cell = found
        if focus != self.focus_target:  # show the state under its own target (GridWorld)
            self.focus_target = focus
            self._ask_figures()
        self.heatmap.step_cell = cell

    def _describe(self, event: Any) -> str:
        if event is None:
            return ""
        session = self.session
        names = session.game.action_names
        action = names[event.action] if 0 <= event.action < len(names) else str(event.action)
        state = session.game.states.describe(event.observation, session.env_kwargs)
        count = f"episode {event.episode:,} · step {event.step:,}" if event.step else ""
        step = f"→ {action}, reward {event.reward:+g}"
        if event.episode_done is not None:
            step += f" · return {event.episode_done.episode_return:+g}"
        # The state comes last: it may take two lines.
        return "\n".join(line for line in (count, step, state) if line)

    # --- events ------------------------------------------------------------
    @on(HeatmapView.FocusChanged)
    def _heatmap_focus(self, event: HeatmapView.FocusChanged) -> None:
        event.stop()
        session = self.session
        row, col = event.cell
        self.focus_target = session.game.layout.focus_at(row, col, session.env_kwargs)
        self._ask_figures()

    @on(HyperparameterForm.Submitted)
    def _form_submitted(self, event: HyperparameterForm.Submitted) -> None:
        event.stop()
        hp = event.hyperparameters
        if hp is None:
            self.app.notify("Fix the highlighted fields first.", severity="error", timeout=3)
            return
        session, runner = self.session, self.runner
        running = runner.running
        done = runner.latest.episodes if running else session.trainer.episodes
        hp, note = continue_run(session.hp, hp, done)
        try:
            runner.set_hyperparameters(hp)  # in force at once, while training runs too
        except ValueError as exc:
            self.app.notify(str(exc), severity="error", timeout=5)
            return
        self.form.load(hp)
        self.progress.show(self.progress.done, hp.episodes)
        applied = "Applied at once: training goes on with them." if running else (
            "Hyperparameters set.")
        self.app.notify(note or applied, timeout=8 if note else 3)
        self._leave_form()

    @on(HyperparameterForm.Left)
    def _form_left(self, event: HyperparameterForm.Left) -> None:
        """Escape: what was typed and not applied goes; the fields show what is in force."""
        event.stop()
        if self.session.hp is not None:
            self.form.load(self.session.hp)
        self._leave_form()

    def _leave_form(self) -> None:
        if self.form.valid:
            self.form.remove_class("-editing")
        self.focus_default()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in ("toggle_traces", "no_traces"):
            return self.session.learner_class.has_traces == (action == "toggle_traces")
        return True

    def action_toggle_traces(self) -> None:
        """The heatmap: Q (V) or the learner's eligibility traces."""
        self.shows_traces = not self.shows_traces
        self._show_heatmap_title()
        self._ask_figures()

    def action_no_traces(self) -> None:
        now = time.monotonic()
        if now < self._no_traces_until:
            return
        self._no_traces_until = now + NO_TRACES_SECONDS
        names = ", ".join(cls.name for cls in ALGORITHMS if cls.has_traces)
        self.app.notify(f"{self.session.learner_class.title} keeps no eligibility traces (the "
                        f"λ learners do: {names}).", severity="warning", timeout=NO_TRACES_SECONDS)

    def action_edit_hyperparameters(self) -> None:
        self.form.add_class("-editing")
        self.form.input("learning_rate").focus()  # at once: the keys typed after `e` go there

    def on_resize(self) -> None:
        compact = self.screen.has_class("compact")
        self._episode.label = "1 ep" if compact else "1 episode"
