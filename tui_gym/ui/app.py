"""The Textual app: a Play view, a Train view and a wrapper side panel over one Session.

`TuiGymApp` owns the `Session` (env, wrappers, agent, trainer) and the runner
that trains it (in a child process, as `tui-gym` opens it, or on a worker
thread). A timer pulls the runner's latest snapshot and hands it to the Train
view; the side panel asks for rebuilds through a message; nothing in the
trainer calls into widgets. `MainScreen` is the app's screen, and
`tune_gc_for_ui` paces the garbage collector for an app that owns its process.
`run_app` runs the app as `tui-gym` does: SIGTERM, SIGHUP and SIGINT end it
cleanly, and an unexpected error ends it with one line and a crash log
(`tui_gym.crash_log`) instead of a traceback on the screen.
"""

from __future__ import annotations

import asyncio
import gc
import os
import signal
import sys
import threading
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

from tui_gym.core.runners import make_runner
from tui_gym.core.session import Session
from tui_gym.core.storage import StorageError
from tui_gym.core.training import continue_run
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games import GAMES, game_named
from tui_gym.ui.help_screen import HelpScreen
from tui_gym.ui.play_view import PlayView
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
        Binding("m", "edit_map", "Map", tooltip="Edit a grid game's map while it trains"),
        # A key for each game in the registry (the help and the side panel's picker list them).
        *(Binding(game.key, f"switch_game('{game.name}')", game.title, show=False)
          for game in GAMES if game.key),
    ]
    TRAIN_ACTIONS = frozenset({"toggle_training", "one_episode", "reset_agent", "faster", "slower"})

    def __init__(
        self,
        session: Session | None = None,
        *,
        play_seed: int | None = None,
        runner: str = "thread",
        tune_gc: bool = False,
        gc_seconds: tuple[float, float] | None = None,
        standalone: bool = False,
    ) -> None:
        """`runner` is "thread" (train on a worker thread) or "process" (a child process;
        what `tui-gym` opens). `tune_gc` applies `tune_gc_for_ui` at mount (for a
        process that runs this one app, as `tui-gym` does; not for test suites),
        collecting every `gc_seconds` (young, full; default `YOUNG_GC_SECONDS`,
        `FULL_GC_SECONDS`). `standalone` is for an app that owns its process and
        terminal (`run_app`): termination signals end it cleanly, and a crash's
        traceback is left to `run_app` to log instead of being printed."""
        super().__init__()
        self.tune_gc = tune_gc
        self.gc_seconds = gc_seconds or (YOUNG_GC_SECONDS, FULL_GC_SECONDS)
        self.gc_pacer: GcPacer | None = None
        self.standalone = standalone
        self.crash: BaseException | None = None  # the first unexpected error, if any
        self.thread_crash: BaseException | None = None  # one from a background thread
        self._signals: list[int] = []
        self.session = session or Session()
        self.runner = make_runner(self.session, runner)
        self.play_seed = self.session.seed if play_seed is None else play_seed
        self._last_version = -1
        self._was_running = False
        self._switcher: ContentSwitcher | None = None

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
            self.gc_pacer = tune_gc_for_ui(self, *self.gc_seconds)
        if self.standalone:
            self._catch_signals()
        self._switcher = self.query_one("#views", ContentSwitcher)
        self.sub_title = self.session.game.title
        self.set_interval(1 / REFRESH_HZ, self._tick)
        self._apply_size(self.size.width, self.size.height)
        self.call_after_refresh(self.play_view.focus_board)

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
        if self.thread_crash is not None:
            raise RuntimeError("a background thread failed") from self.thread_crash
        runner = self.runner
        runner.update()  # take in what the training process handed back
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
        game = game_named(name)
        if game.matches(self.session.env_id):
            self.notify(f"Already playing {game.title}.")
            return
        self.rebuild(env_id=game.env_id)

    async def action_edit_map(self) -> None:
        self.action_show_view("train")
        await self.train_view.open_editor()

    def rebuild_map(self, env_kwargs: dict[str, Any], resized: bool) -> bool:
        """Play an edited map: the agent and training go on where the states keep their
        meaning; a new size resets the agent (with a notice) and training goes on."""
        return self.rebuild(env_kwargs=env_kwargs, quiet=True, keep_running=True)

    def action_focus_wrappers(self) -> None:
        self.side_panel.focus_wrappers()

    def action_toggle_training(self) -> None:
        runner = self.runner
        if runner.running:
            runner.pause(wait=False)
            self.notify("Training paused.", timeout=2)
            return
        if not self._apply_form():
            return
        if runner.start():
            return
        if runner.finished:
            self.notify(
                "The episode budget is used up: raise Episodes or reset the agent (x).",
                severity="warning",
            )
        else:  # no training process can run
            error, runner.error = runner.error, None
            self.notify(f"Cannot train: {error}", severity="error", timeout=10)

    def action_one_episode(self) -> None:
        if self.runner.running:
            self.notify("Pause training first (space).", severity="warning", timeout=3)
            return
        if self._apply_form():
            self.runner.run_one_episode()

    def _apply_form(self) -> bool:
        """Apply the form's hyperparameters (a raised budget continues the run); False when
        a field is wrong."""
        hp = self.train_view.read_hyperparameters()
        if hp is None:
            self.notify("Fix the highlighted fields first.", severity="error")
            return False
        session = self.session
        if hp != session.hp:
            hp, note = continue_run(session.hp, hp, session.trainer.episodes)
            if note:
                self.notify(note, timeout=8)
            session.set_hyperparameters(hp)
            self.train_view.form.load(hp)
        return True

    def action_reset_agent(self) -> None:
        # The thread runner stops within a piece of work; the process runner's child
        # may hand its agent back later, into the old agent: the reset wins.
        self.runner.pause(wait=False)
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
        path = Path.cwd() / f"{self.session.game.name.replace('/', '-')}-agent.tgym"
        self.runner.pause()
        try:
            self.session.save(path)
        except StorageError as exc:
            self.notify(str(exc), severity="error")
            return
        self.notify(f"Agent saved to {path}")

    # --- rebuilding --------------------------------------------------------
    def rebuild(
        self,
        env_id: str | None = None,
        env_kwargs: dict[str, Any] | None = None,
        choices: Sequence[WrapperChoice] | None = None,
        *,
        quiet: bool = False,
        keep_running: bool = False,
    ) -> bool:
        """Rebuild the session's env; False (and a message) when it cannot be built.
        `quiet`: no notice when the agent is kept; `keep_running`: training goes on
        even with a fresh agent."""
        was_running = self.runner.running
        # Never waits on a training process: what it hands back later lands in the
        # agent it was given (kept by a rebuild that keeps it, else dropped).
        self.runner.pause(wait=False)
        try:
            report = self.session.rebuild(env_id=env_id, env_kwargs=env_kwargs, choices=choices)
        except ValueError as exc:
            self.notify(str(exc), severity="error", title="Not applied")
            self.side_panel.reload()
            if was_running:
                self.runner.start()
            return False
        self.sub_title = self.session.game.title
        self._last_version = -1
        self.play_view.reload()
        self.train_view.reload()
        self.side_panel.reload()
        severity = "information" if report.kept_agent else "warning"
        if not (quiet and report.kept_agent):
            self.notify(report.notice, severity=severity, timeout=6)
        if was_running and (report.kept_agent or keep_running):
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
                *((game.key, f"switch to {game.title}") for game in GAMES if game.key),
                ("w / W", "focus the wrapper panel (W while a board that moves with WASD "
                          "has focus)"),
                ("m", "edit the map of a grid game (in the Train view, while it trains)"),
                ("? / F1", "this help"),
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
                (f"Game: {g.title}", g.description,
                 lambda name=g.name: self.action_switch_game(name))
                for g in GAMES
            ),
            ("Start / pause training", "Toggle training", self._palette_toggle),
            ("Reset agent", "Empty Q-table, fresh statistics", self.action_reset_agent),
            ("Save agent", "Save the agent to the current folder", self.action_save_agent),
            ("Wrappers", "Focus the wrapper panel", self.action_focus_wrappers),
            ("Keys", "Every key tui-gym answers to", self.action_help),
        ]
        for title, help_text, callback in commands:
            yield SystemCommand(title, help_text, callback)

    def _palette_toggle(self) -> None:
        if self.current_view != "train":
            self.action_show_view("train")
        self.action_toggle_training()

    async def action_quit(self) -> None:
        self.exit(0)  # the runner closes at unmount, without holding the screen up

    def on_unmount(self) -> None:
        self.runner.close(wait=False)  # `run_app` waits for it once the terminal is back
        loop = asyncio.get_running_loop()
        for signum in self._signals:
            loop.remove_signal_handler(signum)
        self._signals.clear()
        if self.tune_gc:
            gc.enable()  # the timers that collected are gone with the app

    # --- ending well ----------------------------------------------------------
    def _catch_signals(self) -> None:
        """End cleanly (terminal restored, training process closed) on these signals."""
        loop = asyncio.get_running_loop()
        for signum in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT):
            try:
                loop.add_signal_handler(signum, self._end_on_signal, signum)
            except (RuntimeError, ValueError, NotImplementedError):  # not the main thread
                continue
            self._signals.append(signum)

    def _end_on_signal(self, signum: int) -> None:
        self.exit(return_code=128 + signum)

    def _handle_exception(self, error: Exception) -> None:
        # Textual's one path for an unhandled error: it ends the app with code 1 and
        # keeps a traceback to print on the terminal. A standalone app logs it
        # instead (`run_app`), so the person sees one line.
        if self.crash is None:
            self.crash = error
        super()._handle_exception(error)
        if self.standalone:
            self._exit_renderables.clear()


YOUNG_GC_SECONDS = 0.5  # collect the young generations this often
FULL_GC_SECONDS = 20.0  # and everything this often
GC_SECONDS_ENV = "TUI_GYM_GC_SECONDS"  # "YOUNG,FULL" seconds, to override both


class GcPacer:
    """The collections `tune_gc_for_ui` runs on the app's timers, counted."""

    def __init__(self) -> None:
        self.young_collections = 0
        self.full_collections = 0

    # Methods, not `gc.collect` itself: Textual's timers take Python callables only.
    def collect_young(self) -> None:
        gc.collect(1)
        self.young_collections += 1

    def collect_all(self) -> None:
        gc.collect()
        self.full_collections += 1


def tune_gc_for_ui(
    app: App[Any], young_seconds: float = YOUNG_GC_SECONDS, full_seconds: float = FULL_GC_SECONDS
) -> GcPacer:
    """Collect garbage between frames, on the app's own timers.

    Python's collector runs whenever enough objects have been allocated, so
    it often ran in the middle of drawing a frame, when the frame's own
    objects made the collection take up to 25 ms. Here what is alive once the
    app is up moves to the permanent generation (`gc.freeze`: never collected
    again, hence one app a process), automatic collection is off, and timers
    collect the young generations every `young_seconds` (about a
    millisecond) and everything every `full_seconds`; a timer callback
    never runs in the middle of a frame.
    """
    pacer = GcPacer()
    gc.collect()
    gc.freeze()
    gc.disable()
    app.set_interval(young_seconds, pacer.collect_young, name="young-gc")
    app.set_interval(full_seconds, pacer.collect_all, name="full-gc")
    return pacer


def gc_seconds_from_env() -> tuple[float, float] | None:
    """The collection periods set in `TUI_GYM_GC_SECONDS` ("YOUNG,FULL"), or None.

    Raises ValueError with one clear line when the value is not two positive numbers.
    """
    text = os.environ.get(GC_SECONDS_ENV, "").strip()
    if not text:
        return None
    try:
        young, full = (float(part) for part in text.split(","))
    except ValueError:
        young = full = -1.0
    if not (0 < young < 1e6 and 0 < full < 1e6):
        raise ValueError(
            f"{GC_SECONDS_ENV} must be two positive numbers of seconds, "
            f"e.g. 0.5,20; got {text!r}"
        )
    return young, full


EXIT_CRASH = 1


def run_app(
    env_id: str | None = None, seed: int = 0, load: str | None = None, runner: str = "process",
    env_kwargs: dict[str, Any] | None = None,
) -> int:
    """Open the app (from a saved agent with `load`); returns the exit code."""
    gc_seconds = gc_seconds_from_env()
    session = Session.load(load) if load else Session(env_id=env_id or "", seed=seed,
                                                      env_kwargs=env_kwargs or {})
    return run_standalone(
        TuiGymApp(session, runner=runner, tune_gc=True, gc_seconds=gc_seconds, standalone=True)
    )


def run_standalone(app: TuiGymApp) -> int:
    """Run `app` in this terminal until it ends; returns the exit code.

    An unexpected error, in the app or a background thread, ends it with
    `EXIT_CRASH` and one line on stderr naming the crash log that holds the
    traceback; a signal ends it with 128 + the signal's number.
    """
    from tui_gym.crash_log import report_crash

    app.standalone = True
    previous_hook = threading.excepthook

    def thread_failed(args: threading.ExceptHookArgs) -> None:
        if args.exc_value is not None and app.thread_crash is None:
            app.thread_crash = args.exc_value  # raised on the app's next tick

    threading.excepthook = thread_failed
    try:
        app.run()
        error = app.crash or app.thread_crash
        code = app.return_code or 0
    except Exception as exc:  # outside the app's own handling: the same treatment
        error, code = exc, EXIT_CRASH
    finally:
        threading.excepthook = previous_hook
        app.runner.close()
    if error is not None:
        sys.stderr.write(report_crash(error) + "\n")
        return EXIT_CRASH
    return code
