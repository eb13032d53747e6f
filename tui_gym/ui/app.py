"""The Textual app: a Play view, a Train view and a wrapper side panel over one Session.

`TuiGymApp` owns the `Session` (env, wrappers, agent, trainer) and the runner
that trains it (in a child process, as `tui-gym` opens it, or on a worker
thread). A timer pulls the runner's latest snapshot and hands it to the Train
view; the side panel asks for rebuilds through a message; nothing in the
trainer calls into widgets. `MainScreen` is the app's screen, and
`tune_gc_for_ui` paces the garbage collector for an app that owns its process.
"""

from __future__ import annotations

import gc
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, ClassVar

from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.events import Resize
from textual.reactive import Reactive
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import ContentSwitcher, Header, Static

from tui_gym.core.profiles import PROFILES
from tui_gym.core.recording import Recording
from tui_gym.core.recording.switch import RecordingSwitch
from tui_gym.core.runner import make_runner
from tui_gym.core.session import Session
from tui_gym.core.storage import StorageError
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.ui.help_screen import HelpScreen
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.replay_screen import ReplayScreen
from tui_gym.ui.side_panel import SidePanel
from tui_gym.ui.train_view import TrainView
from tui_gym.ui.widgets.key_bar import KeyBar

MIN_WIDTH, MIN_HEIGHT = 80, 24  # below this: a message instead of the layout
COMPACT_WIDTH, COMPACT_HEIGHT = 120, 36  # below this: the compact layout
REFRESH_HZ = 15


class MainScreen(Screen):
    """The app's screen. A focus change repaints the widgets whose look it changes
    (their `:focus` styles), not the whole screen as Textual's `Screen` does: a
    view switch moves the focus, and a whole-screen repaint doubled its cost."""

    focused: Reactive[Widget | None] = Reactive(None, repaint=False)


class TuiGymApp(App[int]):
    """Play, train and tinker: the tui-gym terminal playground."""

    TITLE = "tui-gym"
    CSS_PATH = "app.tcss"

    # The order is the key bar's: what the view does first, then where to go.
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("space", "toggle_training", "Start/Pause", key_display="space"),
        Binding("full_stop", "one_episode", "1 episode", key_display="."),
        Binding("x", "reset_agent", "Reset agent"),
        Binding("plus,equals_sign", "faster", "Faster", key_display="+"),
        Binding("minus,underscore", "slower", "Slower", key_display="-"),
        Binding("p", "show_view('play')", "Play", tooltip="Play the game yourself"),
        Binding("t", "show_view('train')", "Train", tooltip="Watch Q-learning train"),
        Binding("question_mark,f1", "help", "Help", key_display="?"),
        Binding("q", "quit", "Quit"),
        Binding("w,W", "focus_wrappers", "Wrappers", tooltip="Focus the wrapper panel"),
        Binding("b", "switch_game('blackjack')", "Blackjack"),
        Binding("g", "switch_game('gridworld')", "GridWorld"),
        Binding("ctrl+r", "toggle_recording", "Record", show=False),
    ]
    TRAIN_ACTIONS = frozenset({"toggle_training", "one_episode", "reset_agent", "faster", "slower"})

    def __init__(
        self,
        session: Session | None = None,
        *,
        play_seed: int | None = None,
        runner: str = "thread",
        tune_gc: bool = False,
        record: str | Path | None = None,
        replay: Recording | None = None,
    ) -> None:
        """`runner` is "thread" (train on a worker thread) or "process" (a child process;
        what `tui-gym` opens). `tune_gc` applies `tune_gc_for_ui` at mount (for a
        process that runs this one app, as `tui-gym` does; not for test suites).
        `record` records the person's games to that file from the start (ctrl+r
        turns recording on and off); `replay` opens on a recording's replay."""
        super().__init__()
        self.tune_gc = tune_gc
        self.session = session or Session()
        self.runner = make_runner(self.session, runner)
        self.play_seed = self.session.seed if play_seed is None else play_seed
        self._last_version = -1
        self._was_running = False
        self._switcher: ContentSwitcher | None = None
        self.recording = RecordingSwitch(record, on_failure=self._recording_failed)
        self._record_at_start = record is not None
        self._replay = replay

    # --- layout ------------------------------------------------------------
    def get_default_screen(self) -> Screen:
        return MainScreen(id="_default")

    def compose(self) -> ComposeResult:
        yield Header()
        with Horizontal(id="body"):
            with ContentSwitcher(initial="play", id="views"):
                yield PlayView(id="play")
                yield TrainView(id="train")
            yield SidePanel(id="side")
        yield Static(
            f"The terminal is too small for tui-gym.\n"
            f"It needs at least {MIN_WIDTH}×{MIN_HEIGHT}; make the window larger.",
            id="too-small",
        )
        yield KeyBar()

    def on_mount(self) -> None:
        if self.tune_gc:
            tune_gc_for_ui(self)
        self._switcher = self.query_one("#views", ContentSwitcher)
        self.sub_title = self.session.profile.title
        self.set_interval(1 / REFRESH_HZ, self._tick)
        self._apply_size(self.size.width, self.size.height)
        self.call_after_refresh(self.play_view.focus_board)
        if self._record_at_start:
            self.call_after_refresh(self.action_toggle_recording)
        if self._replay is not None:
            self.push_screen(ReplayScreen(self._replay))

    def on_resize(self, event: Resize) -> None:
        self._apply_size(event.size.width, event.size.height)

    def _apply_size(self, width: int, height: int) -> None:
        screen = self.screen
        screen.set_class(width < MIN_WIDTH or height < MIN_HEIGHT, "too-small")
        screen.set_class(width < COMPACT_WIDTH or height < COMPACT_HEIGHT, "compact")

    @property
    def play_view(self) -> PlayView:
        return self.query_one(PlayView)

    @property
    def train_view(self) -> TrainView:
        return self.query_one(TrainView)

    @property
    def side_panel(self) -> SidePanel:
        return self.query_one(SidePanel)

    @property
    def current_view(self) -> str:
        """"play" or "train" (asked often: by every binding check and every tick)."""
        switcher = self._switcher
        if switcher is None or not switcher.is_attached:  # not yet, or being taken apart
            return "play"
        return switcher.current or "play"

    # --- the timer: pull the latest snapshot --------------------------------
    def _tick(self) -> None:
        runner = self.runner
        if runner.error is not None:
            error, runner.error = runner.error, None
            self.notify(f"Training stopped: {error}", severity="error", timeout=8)
        running = runner.running
        if running != self._was_running:
            self._was_running = running
            if not running and runner.finished:
                self.notify("Training reached its episode budget.", title="Done")
        if self.current_view != "train":
            return
        snapshot = runner.latest
        if snapshot.version != self._last_version or running:
            self._last_version = snapshot.version
            self.train_view.show_snapshot(snapshot, runner)

    # --- actions -----------------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in self.TRAIN_ACTIONS:
            return self.current_view == "train"
        return True

    def action_show_view(self, view: str) -> None:
        if self._switcher is None:
            return
        self._switcher.current = view
        if view == "play":
            self.play_view.focus_board()
        else:
            self._last_version = -1
            self.train_view.focus_default()
            self._tick()
        self.refresh_bindings()  # the view's keys, even when the focus stays put

    def action_switch_game(self, name: str) -> None:
        profile = next(p for p in PROFILES if p.name == name)
        if profile.env_id == self.session.env_id:
            self.notify(f"Already playing {profile.title}.")
            return
        self.rebuild(env_id=profile.env_id)

    def action_focus_wrappers(self) -> None:
        self.side_panel.focus_wrappers()

    def action_toggle_training(self) -> None:
        if self.runner.running:
            self.runner.pause(wait=False)
            self.notify("Training paused.", timeout=2)
            return
        hp = self.train_view.read_hyperparameters()
        if hp is None:
            self.notify("Fix the highlighted fields first.", severity="error")
            return
        self.session.set_hyperparameters(hp)
        if not self.runner.start():
            self.notify(
                "The episode budget is used up: raise Episodes or reset the agent (x).",
                severity="warning",
            )

    def action_one_episode(self) -> None:
        if self.runner.running:
            self.notify("Pause training first (space).", severity="warning", timeout=3)
            return
        hp = self.train_view.read_hyperparameters()
        if hp is None:
            self.notify("Fix the highlighted fields first.", severity="error")
            return
        self.session.set_hyperparameters(hp)
        self.runner.run_one_episode()

    def action_reset_agent(self) -> None:
        self.runner.pause()
        self.session.reset_agent()
        self._last_version = -1
        self.train_view.reload()
        self.notify("Agent reset: empty Q-table, fresh statistics.")

    def action_faster(self) -> None:
        speed = self.runner.faster()
        self.train_view.show_speed(speed.name)

    def action_slower(self) -> None:
        speed = self.runner.slower()
        self.train_view.show_speed(speed.name)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen(self.key_help()))

    def action_save_agent(self) -> None:
        path = Path.cwd() / f"{self.session.profile.name}-agent.tgym"
        self.runner.pause()
        try:
            self.session.save(path)
        except StorageError as exc:
            self.notify(str(exc), severity="error")
            return
        self.notify(f"Agent saved to {path}")

    # --- recording ---------------------------------------------------------------
    def action_toggle_recording(self) -> None:
        """Record the person's games to a file, or stop."""
        game = self.play_view.game
        if self.recording.on:
            path = self.recording.turn_off()
            self.play_view.show_recording("")
            self.notify(f"Recording stopped: {path}", timeout=4)
            return
        if game is None:
            return
        try:
            path = self.recording.turn_on(game)
        except OSError as exc:
            self.notify(f"Cannot record to {exc.filename or self.recording.path}: "
                        f"{exc.strerror or exc}", severity="error", title="Not recording")
            return
        self.play_view.show_recording(path.name)
        noun = game.profile.episode_noun
        when = "" if self.recording.recorder and self.recording.recorder.episode_open else (
            f" from the next {noun}"
        )
        self.notify(f"Recording your {noun}s to {path}{when} (ctrl+r stops).", timeout=5)

    def _recording_failed(self, message: str) -> None:
        self.play_view.show_recording("")
        self.notify(message, severity="error", title="Not recording", timeout=10)

    # --- rebuilding --------------------------------------------------------
    def rebuild(
        self,
        env_id: str | None = None,
        env_kwargs: dict[str, Any] | None = None,
        choices: Sequence[WrapperChoice] | None = None,
    ) -> bool:
        """Rebuild the session's env; False (and a message) when it cannot be built."""
        was_running = self.runner.running
        self.runner.pause()
        try:
            report = self.session.rebuild(env_id=env_id, env_kwargs=env_kwargs, choices=choices)
        except ValueError as exc:
            self.notify(str(exc), severity="error", title="Not applied")
            self.side_panel.reload()
            if was_running:
                self.runner.start()
            return False
        self.sub_title = self.session.profile.title
        self._last_version = -1
        self.play_view.reload()
        self.train_view.reload()
        self.side_panel.reload()
        severity = "information" if report.kept_agent else "warning"
        self.notify(report.notice, severity=severity, timeout=6)
        if was_running and report.kept_agent:
            self.runner.start()
        return True

    def on_side_panel_changed(self, message: SidePanel.Changed) -> None:
        self.rebuild(env_id=message.env_id, env_kwargs=message.env_kwargs, choices=message.choices)

    # --- help and the command palette ---------------------------------------
    def key_help(self) -> list[tuple[str, list[tuple[str, str]]]]:
        """Every key, grouped by where it works: (section, [(key, what it does)])."""
        sections = [
            ("Everywhere", [
                ("p / t", "Play view / Train view"),
                ("b / g", "switch to Blackjack / GridWorld"),
                ("w / W", "focus the wrapper panel (W while the GridWorld board has focus)"),
                ("? / F1", "this help"),
            ("ctrl+r", "record your games to a file / stop (tui-gym replay FILE plays it back)"),
                ("ctrl+p", "command palette"),
                ("q", "quit"),
            ]),
            ("Play", self.play_view.key_help()),
            ("Train", [
                ("space", "start / pause training"),
                (".", "run one episode"),
                ("x", "reset the agent"),
                ("+ / -", "faster / slower (animated ... max)"),
                *self.train_view.key_help(),
            ]),
            ("Side panel", [
                ("tab / shift+tab", "move between fields"),
                ("space / enter", "tick a wrapper, press a button"),
                ("enter", "apply a parameter"),
            ]),
        ]
        return sections

    def get_system_commands(self, screen: Screen) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        commands = [
            ("Play view", "Play the game yourself", lambda: self.action_show_view("play")),
            ("Train view", "Watch Q-learning learn", lambda: self.action_show_view("train")),
            *(
                (f"Game: {p.title}", p.description,
                 lambda name=p.name: self.action_switch_game(name))
                for p in PROFILES
            ),
            ("Start / pause training", "Toggle training", self._palette_toggle),
            ("Reset agent", "Empty Q-table, fresh statistics", self.action_reset_agent),
            ("Save agent", "Save the agent to the current folder", self.action_save_agent),
            ("Wrappers", "Focus the wrapper panel", self.action_focus_wrappers),
            ("Keys", "Every key tui-gym answers to", self.action_help),
            ("Record games", "Record your games to a file, or stop (ctrl+r)",
             self.action_toggle_recording),
        ]
        for title, help_text, callback in commands:
            yield SystemCommand(title, help_text, callback)

    def _palette_toggle(self) -> None:
        if self.current_view != "train":
            self.action_show_view("train")
        self.action_toggle_training()

    async def action_quit(self) -> None:
        self.recording.turn_off()
        self.runner.close()
        self.exit(0)

    def on_unmount(self) -> None:
        self.recording.turn_off()
        self.runner.close()
        if self.tune_gc:
            gc.enable()  # the timers that collected are gone with the app


YOUNG_GC_SECONDS = 0.5  # collect the young generations this often
FULL_GC_SECONDS = 20.0  # and everything this often


def tune_gc_for_ui(app: App[Any]) -> None:
    """Collect garbage between frames, on the app's own timers.

    Python's collector runs whenever enough objects have been allocated, so
    it often ran in the middle of drawing a frame, when the frame's own
    objects made the collection take up to 25 ms. Here what is alive once the
    app is up moves to the permanent generation (`gc.freeze`: never collected
    again, hence one app a process), automatic collection is off, and timers
    collect the young generations every `YOUNG_GC_SECONDS` (about a
    millisecond) and everything every `FULL_GC_SECONDS`; a timer callback
    never runs in the middle of a frame.
    """
    gc.collect()
    gc.freeze()
    gc.disable()
    app.set_interval(YOUNG_GC_SECONDS, lambda: gc.collect(1), name="young-gc")
    app.set_interval(FULL_GC_SECONDS, gc.collect, name="full-gc")


def run_app(
    env_id: str = "Blackjack-v1", seed: int = 0, load: str | None = None, runner: str = "process",
    *, session: Session | None = None, record: str | None = None,
    replay: Recording | None = None,
) -> int:
    """Open the app (from a saved agent with `load`, or on `session`); returns the exit code.
    `record` records the person's games to that file; `replay` opens on a recording."""
    if session is None:
        session = Session.load(load) if load else Session(env_id=env_id, seed=seed)
    app = TuiGymApp(session, runner=runner, tune_gc=True, record=record, replay=replay)
    result = app.run()
    return int(result or 0)
