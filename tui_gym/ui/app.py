"""The Textual app: Play, Train, Compare, Plan and Book views and a wrapper side panel.

`TuiGymApp` keeps one `Session` per game for the whole run and the runner that trains
the one shown; `run_app` runs it as `tui-gym` does (signals and a closed terminal end it
cleanly, an unexpected error with one line and a crash log).
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import os
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from functools import partial
from itertools import zip_longest
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.driver import Driver
from textual.events import Resize
from textual.notifications import Notification, Notify, SeverityLevel
from textual.screen import Screen
from textual.widget import AwaitMount
from textual.widgets import ContentSwitcher, Header

from tui_gym.core.engine.trainer import continue_run
from tui_gym.core.text import visible
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games import GAMES, Game, game_for, game_named
from tui_gym.games.words import plural
from tui_gym.session.recording.switch import RecordingSwitch
from tui_gym.session.runners import make_runner
from tui_gym.session.session import Session
from tui_gym.session.speeds import SPEEDS
from tui_gym.session.storage import StorageError
from tui_gym.ui.exact_figures import KEY_QUIET_SECONDS
from tui_gym.ui.key_order import KeysInOrder
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.side_panel import SidePanel
from tui_gym.ui.textual_internals import (
    CrashHook,
    TerminalGone,
    guarded_driver,
    main_screen,
    terminal_write_failed,
)
from tui_gym.ui.too_small_screen import TooSmallScreen
from tui_gym.ui.widgets.key_bar import KeyBar

if TYPE_CHECKING:
    from tui_gym.core.recording import Recording
    from tui_gym.session.experiments.app_recording import SessionRunLog
    from tui_gym.ui.compare_view import CompareView
    from tui_gym.ui.plan_view import PlanView
    from tui_gym.ui.train_view import TrainView


MIN_WIDTH, MIN_HEIGHT = 80, 24  # below this: a message instead of the layout
COMPACT_WIDTH, COMPACT_HEIGHT = 120, 36  # below this: the compact layout
REFRESH_HZ = 15
# The speed a step key switches to: the first animated one that is not the slowest.
ANIMATED_SPEED = next(i for i, speed in enumerate(SPEEDS) if speed.name == "animated")
IDLE_POLL = 0.02  # seconds between looks for the agent handed back before a change
IDLE_TIMEOUT = 10.0  # and how long to look before giving up
LOADING_NOTICE = 0.3  # seconds a new game's build takes before the app says it is loading


# Each view: its name, its key, its label and what it shows (its binding and its palette command).
VIEWS = (
    ("play", "p", "Play", "Play the game yourself"),
    ("train", "t", "Train", "Watch the agent learn"),
    ("compare", "v", "Compare", "Compare learners across seeds; the runs recorded for this game"),
    ("plan", "P", "Plan", "Policy evaluation, policy iteration and value iteration on the "
                          "game's exact model, sweep by sweep"),
    ("book", "f", "Book", "Sutton & Barto's figures: learners run over seeds, the book's claims "
                          "checked"),
)
GAME_KEYS_A_LINE = 8  # the help's game keys, a line of at most this many


def _game_keys() -> list[tuple[str, str]]:
    """The help's rows of game keys: a few a line, so the key column stays narrow."""
    keys = [g.key for g in GAMES if g.key]
    lines = [" ".join(keys[i:i + GAME_KEYS_A_LINE])
             for i in range(0, len(keys), GAME_KEYS_A_LINE)]
    words = ["switch game, as the picker names them;",
             "each keeps its agent, settings and curves"]
    if len(lines) < len(words):
        return [(lines[0], " ".join(words))]
    return list(zip_longest(lines, words, fillvalue=""))


class TuiGymApp(KeysInOrder, CrashHook, App[int]):
    """Play, train and tinker: the tui-gym terminal playground."""

    TITLE = "tui-gym"
    CSS_PATH = "app.tcss"

    # The order is the key bar's: what the view does first, then where to go.
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("space", "toggle_training", "Start/Pause", key_display="space"),
        Binding("full_stop", "one_episode", "1 episode", key_display="."),
        Binding("n", "one_step", "1 step", tooltip="One transition, explained step by step"),
        Binding("x", "request_reset", "Reset agent"),
        Binding("plus,equals_sign", "faster", "Faster", key_display="+"),
        Binding("minus,underscore", "slower", "Slower", key_display="-"),
        *(Binding(key, f"show_view('{view}')", label, tooltip=what)
          for view, key, label, what in VIEWS),
        Binding("question_mark,f1", "help", "Help", key_display="?"),
        Binding("q", "quit", "Quit"),
        Binding("w,W", "focus_wrappers", "Wrappers", tooltip="Focus the wrapper panel"),
        Binding("m", "edit_map", "Map", tooltip="Edit a grid game's map while it trains"),
        # A key for each game in the registry (the help and the side panel's picker list them).
        *(Binding(game.key, f"switch_game('{game.name}')", game.title, show=False)
          for game in GAMES if game.key),
        Binding("ctrl+s", "save_agent", "Save agent", show=False),
        Binding("ctrl+o", "load_agent", "Load agent", show=False),
        Binding("ctrl+r", "toggle_recording", "Record", show=False),
    ]
    TRAIN_ACTIONS = frozenset(
        {"toggle_training", "one_episode", "one_step", "reset_agent", "request_reset", "faster",
         "slower"}
    )

    def __init__(
        self,
        session: Session | None = None,
        *,
        runner: str = "thread",
        tune_gc: bool = False,
        gc_seconds: tuple[float, float] | None = None,
        standalone: bool = False,
        record: str | Path | None = None,
        replay: Recording | None = None,
        run_log: SessionRunLog | Callable[[], SessionRunLog] | None = None,
        db: str | Path | None = None,
        history_kept: bool = True,
    ) -> None:
        """`runner`: "thread" or "process"; `tune_gc`: `tune_gc_for_ui` at mount, every
        `gc_seconds` (young, full); `standalone`: the app owns its process and terminal
        (`run_app`); `record`: record the person's games to that file; `replay`: open on a
        recording; `run_log`: the run history the runs trained here go to (a function: made
        after the first frame); `db`: the Compare view's history (`history_kept` False: a
        scratch file)."""
        super().__init__()
        self.tune_gc = tune_gc
        self.gc_seconds = gc_seconds or (YOUNG_GC_SECONDS, FULL_GC_SECONDS)
        self.gc_pacer: GcPacer | None = None
        self.standalone = standalone
        self.thread_crash: BaseException | None = None  # one from a background thread
        self._signals: list[int] = []
        self.session = session or Session()
        self.runner = make_runner(self.session, runner)
        self.play_seed = self.session.seed
        self._sessions: dict[str, Session] = {self.session.game.name: self.session}
        self._building: set[str] = set()  # games whose new session a worker builds
        self._fresh: set[str] = set()  # games whose session is new, not yet shown
        self._wanted_game = self.session.game.name  # the game last asked for
        self._files: dict[str, Path] = {}  # the last file each game was saved to or loaded from
        self._loaded: tuple[Session, Path] | None = None  # read, waiting to be put in place
        self._too_small: TooSmallScreen | None = None
        self._last_version = -1
        self._train_appearing = False  # shown, its first frame not yet drawn
        self._was_running = False
        self._switcher: ContentSwitcher | None = None
        self.recording = RecordingSwitch(record, on_failure=self._recording_failed)
        self._record_at_start = record is not None
        self._replay = replay
        self.run_log = run_log if not callable(run_log) else None
        self._make_run_log = run_log if callable(run_log) else None
        self.db = db
        self.history_kept = history_kept
        self._views: dict[str, Any] = {}  # the Compare, Plan and Book views, once shown
        self._train: TrainView | None = None
        self._train_mounted: AwaitMount | None = None
        self._notices: dict[tuple[str, str, str], Notification] = {}  # the last of each

    def notify(self, message: str, *, title: str = "", severity: SeverityLevel = "information",
               timeout: float | None = None, markup: bool = True) -> None:
        """A notice; the same notice again while it shows takes its place (a burst of keys
        that each say the same leaves one notice, not a stack of them)."""
        notice = Notification(message, title, severity,
                              self.NOTIFICATION_TIMEOUT if timeout is None else timeout, markup)
        self._notices = {key: n for key, n in self._notices.items() if not n.has_expired}
        shown = self._notices.get((message, title, severity))
        if shown is not None:
            notice.identity = shown.identity
        self._notices[message, title, severity] = notice
        self.post_message(Notify(notice))

    # --- layout ------------------------------------------------------------
    def get_default_screen(self) -> Screen:
        self._main_screen = main_screen(id="_default")
        self._size_classes(self.size.width, self.size.height)  # styled at its size from the start
        return self._main_screen

    def get_driver_class(self) -> type[Driver]:
        return guarded_driver(super().get_driver_class())

    @property
    def quiet_crash(self) -> bool:  # type: ignore[override]
        """An app that owns its terminal logs a crash's traceback instead (`run_app`)."""
        return self.standalone

    def compose(self) -> ComposeResult:
        yield Header()
        with Horizontal(id="body"):
            with ContentSwitcher(initial="play", id="views"):
                yield PlayView(id="play")
            yield SidePanel(id="side")
        yield KeyBar()

    def on_mount(self) -> None:
        if self.standalone:
            self._catch_signals()
        self._switcher = self.query_one("#views", ContentSwitcher)
        self._show_title()
        self.set_interval(1 / REFRESH_HZ, self._tick)
        self._apply_size(self.size.width, self.size.height)
        self.call_after_refresh(self._focus_at_start)
        self.call_after_refresh(self._after_first_frame)
        if self._record_at_start:
            self.call_after_refresh(self.action_toggle_recording)
        if self._replay is not None:
            from tui_gym.ui.replay_screen import ReplayScreen

            self.push_screen(ReplayScreen(self._replay))

    def _after_first_frame(self) -> None:
        """What the first frame need not wait for: the Train view, the run history, then
        the collector tuned."""
        self._ensure_train()
        if self._make_run_log is not None:
            self.run_log, self._make_run_log = self._make_run_log(), None
        if self.tune_gc:
            self.call_after_refresh(self._tune_gc)

    def _show_title(self) -> None:
        """The header: the game and the seed (`--seed` repeats a run)."""
        self.sub_title = f"{self.session.game.title} · seed {self.session.seed}"

    def _tune_gc(self) -> None:
        if self.gc_pacer is None and self.is_running:
            self.gc_pacer = tune_gc_for_ui(self, *self.gc_seconds)

    def on_resize(self, event: Resize) -> None:
        self._apply_size(event.size.width, event.size.height)

    def _size_classes(self, width: int, height: int) -> bool:
        """Give the main screen (whatever screen is on top) the layout's classes for this
        terminal size; whether it is too small for the app."""
        screen = self._main_screen
        small = width < MIN_WIDTH or height < MIN_HEIGHT
        screen.set_class(small, "too-small")
        screen.set_class(width < COMPACT_WIDTH or height < COMPACT_HEIGHT, "compact")
        return small

    def _apply_size(self, width: int, height: int) -> None:
        small = self._size_classes(width, height)
        self._show_side()
        if small and self._too_small is None:
            self._too_small = TooSmallScreen(MIN_WIDTH, MIN_HEIGHT)
            self.push_screen(self._too_small)
        elif not small and self._too_small is not None:
            if self.screen is self._too_small:
                self.pop_screen()
            self._too_small = None

    @property
    def play_view(self) -> PlayView:
        return self.query_one(PlayView)

    @property
    def train_view(self) -> TrainView:
        """The Train view (built, and mounted, the first time it is asked for)."""
        return self._ensure_train()

    def _ensure_train(self) -> TrainView:
        view = self._train
        if view is None:
            from tui_gym.ui.train_view import TrainView

            view = self._train = TrainView(id="train")
            view.display = self.current_view == "train"
            assert self._switcher is not None
            if self._switcher.is_attached:  # else the app is being taken apart
                self._train_mounted = self._switcher.mount(view)  # it reads the session then
        return view

    async def _mounted_train(self) -> TrainView:
        """The Train view, once it is mounted."""
        view = self._ensure_train()
        if self._train_mounted is not None:
            await self._train_mounted
        return view

    def _train_ready(self) -> TrainView | None:
        """The Train view once it is mounted, else None (it reads the session as it mounts)."""
        view = self._train
        return view if view is not None and view.is_mounted else None

    @property
    def compare_view(self) -> CompareView | None:
        """The Compare view, once it has been shown (it is built the first time)."""
        return self._views.get("compare")

    @property
    def plan_view(self) -> PlanView | None:
        """The Plan view, once it has been shown (it is built the first time)."""
        return self._views.get("plan")

    def _show_session(self) -> None:
        """Every view, and the keys the game offers (`m` for a map), follow the session."""
        self._show_title()
        self.play_view.reload()
        self._reload_train()
        if (compare := self.compare_view) is not None:
            compare.reload()
        if (plan := self.plan_view) is not None and plan.is_mounted:
            plan.reload()
        self.side_panel.reload()
        self.refresh_bindings()

    @property
    def side_panel(self) -> SidePanel:
        return self.query_one(SidePanel)

    @property
    def current_view(self) -> str:
        """"play", "train", "compare", "plan" or "book" (asked often: by every binding check
        and every tick)."""
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
        if self.run_log is not None:
            notice = self.run_log.observe(self.session, runner.latest)
            if notice:
                self.notify(notice, severity="warning", title="Run history", timeout=8)
        running = runner.running
        if running != self._was_running:
            self._was_running = running
            if not running and runner.finished:
                self.notify("Training reached its episode budget.", title="Done")
        view = self._train_ready()
        if view is None or self.current_view != "train" or self._train_appearing:
            return
        snapshot = runner.latest
        if snapshot.version != self._last_version or running:
            view.show_snapshot(snapshot, runner)
            self._last_version = view.shown_version  # one held back is offered again

    # --- actions -----------------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if self._too_small is not None:
            return action == "quit"  # nothing else behind a screen that hides the app
        if action in self.TRAIN_ACTIONS:
            return self.current_view == "train"
        if action == "edit_map":  # offered only where the game has a map
            return self.session.game.editable
        return True

    def action_show_view(self, view: str) -> None:
        if self._switcher is None:
            return
        compare = self.compare_view
        if view != "compare" and compare is not None and compare.stop_comparison():
            self.notify("Comparison stopped: what finished is recorded.", timeout=4)
        if view == "train":
            self._ensure_train()
        elif view != "play" and view not in self._views:
            # Built (and imported) the first time it shows: most runs of the app never open
            # them. The Compare view reads the history and takes the focus at mount.
            self._views[view] = self._new_view(view)
            self._switcher.mount(self._views[view])
        self._switcher.current = view
        focused = self.focused
        if focused is not None and self._switcher in focused.ancestors \
                and self._switcher.visible_content not in focused.ancestors:
            # Keys typed before the view takes the keyboard (once mounted) are the app's,
            # not those of the view just hidden.
            self.set_focus(None)  # the keys shown follow the focus: the view's, from here
        else:
            self.refresh_bindings()  # the view's keys, even when the focus stays put
        self._show_side()
        if view == "play":
            self.play_view.focus_board()
        elif view == "compare":
            compare = self._views[view]
            if compare.is_mounted:
                compare.reload(fresh=True)
                compare.focus_default()
        elif view in ("plan", "book"):
            self.call_after_refresh(self._focus_shown, view)
        else:
            self._train_shown()

    def _new_view(self, view: str) -> Any:
        """The Compare, Plan or Book view."""
        if view == "compare":
            from tui_gym.ui.compare_view import CompareView

            return CompareView(id="compare", db=self.db, kept=self.history_kept)
        if view == "plan":
            from tui_gym.ui.plan_view import PlanView

            return PlanView(id="plan")
        from tui_gym.ui.book_view import BookView

        return BookView(id="book")

    def _train_shown(self) -> None:
        """The Train view takes the keyboard (once mounted); the latest snapshot is drawn
        after the frame that shows it, so a view switch waits for one drawing, not two."""
        if self.current_view != "train":
            return
        view = self._train_ready()
        if view is None:
            self.call_after_refresh(self._train_shown)
            return
        view.focus_default()
        self._train_appearing = True
        self.call_after_refresh(self._train_appeared)

    def _train_appeared(self) -> None:
        self._train_appearing = False
        self._last_version = -1
        self._tick()

    def action_switch_game(self, name: str) -> None:
        game = game_named(name)
        if game is self.session.game:
            if self._wanted_game == game.name:
                self.notify(f"Already playing {game.title}.")
            self._wanted_game = game.name  # a switch still waiting for training is dropped
            return
        self.switch_game(game)

    async def action_edit_map(self) -> None:
        if self.current_view == "plan" and (plan := self.plan_view) is not None:
            plan.open_editor()  # it plans on beside the editor
            return
        self.action_show_view("train")
        view = await self._mounted_train()
        await view.open_editor()

    def rebuild_map(self, env_kwargs: dict[str, Any]) -> bool:
        """Play an edited map: the agent and training go on where the states keep their
        meaning; a new size resets the agent (with a notice) and training goes on."""
        return self.rebuild(env_kwargs=env_kwargs, quiet=True, keep_running=True)

    def _focus_shown(self, view: str) -> None:
        """A view's keys once it is drawn, unless a key typed since went elsewhere."""
        if self.current_view == view and not self.side_panel.has_focus_within:
            self.action_focus_view()

    def _show_side(self) -> None:
        """The side panel, but in the compact Compare and Book views (its display: a class
        of the screen would restyle every widget on it)."""
        if self._switcher is not None:
            wide = self.current_view in ("compare", "book")
            self.side_panel.display = not (wide and self._main_screen.has_class("compact"))

    async def action_focus_wrappers(self) -> None:
        self.side_panel.display = True  # back beside a view that takes the whole width
        await self.side_panel.focus_wrappers()

    def action_focus_view(self) -> None:
        """Give the keyboard back to the view shown (its board, or the heatmap)."""
        if self.current_view == "play":
            self.play_view.focus_board()
        elif (built := self._views.get(self.current_view)) is not None:
            if built.is_mounted:
                built.focus_default()
            else:  # still being built: once it is
                self.call_after_refresh(self._focus_shown, self.current_view)
        elif (view := self._train_ready()) is not None:
            view.focus_default()  # else it takes the keyboard when it mounts

    def _focus_at_start(self) -> None:
        """The view's keys from the first frame, unless a key already moved the focus."""
        if self.focused is None:
            self.action_focus_view()

    def on_side_panel_left(self, message: SidePanel.Left) -> None:
        self._show_side()
        self.action_focus_view()

    # --- one session per game -------------------------------------------------
    def switch_game(
        self, game: Game, otherwise: Callable[[], None] | None = None
    ) -> None:
        """Play `game`: its session from earlier in this run or a new one, built off the
        event loop; `otherwise` runs if the agent is not handed back or the game not built."""
        self._wanted_game = game.name
        if game.name in self._sessions:
            was_running = self.runner.running
            self._when_idle(lambda: self._switch_now(game, was_running), otherwise)
        elif game.name not in self._building:
            self._building.add(game.name)
            current = self.session
            self.run_worker(lambda: self._build_session(game, current, otherwise),
                            thread=True, exit_on_error=False, group="sessions")
            self.set_timer(LOADING_NOTICE, lambda: self._say_loading(game))

    def _build_session(
        self, game: Game, current: Session, otherwise: Callable[[], None] | None
    ) -> None:
        """A new session for `game` (in a worker thread), handed to the event loop."""
        built: Session | Exception
        try:
            built = Session(game.env_id, seed=current.seed, engine=current.engine)
        except Exception as exc:  # noqa: BLE001  (a game that cannot be built is said)
            built = exc
        self.call_from_thread(self._built, game, built, otherwise)

    def _built(
        self, game: Game, built: Session | Exception, otherwise: Callable[[], None] | None
    ) -> None:
        self._building.discard(game.name)
        if isinstance(built, Exception):
            self.notify(f"{game.title} could not start: {visible(str(built), 200)}",
                        severity="error")
            if otherwise is not None:
                otherwise()
            return
        if self._sessions.setdefault(game.name, built) is built:  # not loaded meanwhile
            self._fresh.add(game.name)
        if self._wanted_game == game.name:  # no other game asked for meanwhile
            self.switch_game(game, otherwise)

    def _say_loading(self, game: Game) -> None:
        if game.name in self._building and self._wanted_game == game.name:
            self.notify(f"Loading {game.title}…", timeout=2)

    def _switch_now(self, game: Game, was_running: bool) -> None:
        if game is self.session.game or self._wanted_game != game.name:
            return  # two switches asked for in a row, or another game asked for since
        session = self._sessions[game.name]
        fresh = game.name in self._fresh
        self._fresh.discard(game.name)
        self.play_view.put_away()
        self._use_session(session)
        if fresh:
            notice = f"{game.title}: a new agent with the game's own settings."
        else:
            episodes = session.trainer.episodes
            notice = (f"{game.title}: your agent ({plural(episodes, 'episode')}), settings "
                      "and wrappers as you left them.")
        if was_running:
            notice = "Training paused. " + notice
        self.notify(notice, timeout=5)

    def _when_idle(
        self,
        then: Callable[[], None],
        otherwise: Callable[[], None] | None = None,
        deadline: float | None = None,
    ) -> None:
        """Pause training and run `then` once the runner has the agent back, never blocking
        the UI; after `IDLE_TIMEOUT` it says so and runs `otherwise`."""
        runner = self.runner
        if deadline is None:
            runner.pause(wait=False)
            deadline = time.monotonic() + IDLE_TIMEOUT
        if runner.wait_idle(0):
            then()
        elif time.monotonic() > deadline:
            self.notify("Training did not hand the agent back; nothing was changed.",
                        severity="error")
            if otherwise is not None:
                otherwise()
        else:
            self.set_timer(IDLE_POLL, lambda: self._when_idle(then, otherwise, deadline))

    def _use_session(self, session: Session) -> None:
        """Make `session` the one shown and trained (the runner is paused)."""
        self.session = session
        runner = self.runner
        runner.session = session  # both runners read their session afresh at each start
        runner.finished = False
        with contextlib.suppress(AttributeError):  # read-only where tied to the agent
            # The other game's last move.
            runner.last_event = runner.last_scene = None  # type: ignore[misc]
        self._show_session()

    def _episodes_trained(self) -> int:
        """Episodes the current agent has trained (the runner's count while it trains)."""
        return max(self.runner.latest.episodes, self.session.trainer.episodes)

    # --- what would lose a trained agent asks first -----------------------------
    def action_request_reset(self) -> None:
        """Reset the agent; when it has trained, only once the person confirms."""
        episodes = self._episodes_trained()
        self._ask_first(
            episodes > 0, "Reset the agent?",
            f"It has trained {plural(episodes, 'episode')}. An empty Q-table and fresh "
            "statistics replace them (ctrl+s saves it first).", "Reset", self.action_reset_agent,
        )

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
            self._budget_used_up()
        else:  # no training process can run
            error, runner.error = runner.error, None
            self.notify(f"Cannot train: {error}", severity="error", timeout=10)

    def action_one_episode(self) -> None:
        if self._paused_and_applied() and not self.runner.run_one_episode():
            self._budget_used_up()

    def _paused_and_applied(self) -> bool:
        """Whether one episode or step may run: training paused (else it says so) and the
        form's values applied."""
        if self.runner.running:
            self.notify("Pause training first (space).", severity="warning", timeout=3)
            return False
        return self._apply_form()

    def _budget_used_up(self) -> None:
        self.notify("The episode budget is used up: raise Episodes or reset the agent (x).",
                    severity="warning")

    def action_one_step(self) -> None:
        """One transition on the env, explained in the Train view's step panel (the speed
        goes to animated, where the panel and the board show)."""
        runner = self.runner
        if not self._paused_and_applied():
            return
        if not runner.run_one_step():
            self._budget_used_up()
            return
        if not runner.speed.animated:
            speed = runner.set_speed(ANIMATED_SPEED)
            self._show_speed(speed.name)
            self.notify(f"Speed: {speed.name}, so each step shows on the board and in the "
                        "step panel.", timeout=4)

    def _apply_form(self) -> bool:
        """Apply the form's hyperparameters (a raised budget continues the run); False when
        a field is wrong."""
        view = self._train_ready()
        if view is None:
            return True  # no form yet: nothing typed to apply
        hp = view.read_hyperparameters()
        if hp is None:
            self.notify("Fix the highlighted fields first.", severity="error")
            return False
        session = self.session
        if hp != session.hp:
            hp, note = continue_run(session.hp, hp, session.trainer.episodes)
            if note:
                self.notify(note, timeout=8)
            session.set_hyperparameters(hp)
            view.form.load(hp)
        return True

    def action_reset_agent(self) -> None:
        # The thread runner stops within a piece of work; the process runner's child
        # may hand its agent back later, into the old agent: the reset wins.
        self.runner.pause(wait=False)
        self.session.reset_agent()
        self._reload_train()
        self.notify("Agent reset: empty Q-table, fresh statistics.")

    def action_faster(self) -> None:
        self._show_speed(self.runner.faster().name)

    def action_slower(self) -> None:
        self._show_speed(self.runner.slower().name)

    def _show_speed(self, name: str) -> None:
        if (view := self._train_ready()) is not None:
            view.show_speed(name)  # else it reads the runner's speed when it mounts

    def _reload_train(self) -> None:
        """Show the session afresh in the Train view (one not yet mounted reads it then)."""
        self._last_version = -1
        if (view := self._train_ready()) is not None:
            view.reload()

    async def action_help(self) -> None:
        await self._mounted_train()  # the help lists the Train view's keys too
        from tui_gym.ui.help_screen import HelpScreen

        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen(self.key_help()))

    # --- files -----------------------------------------------------------------
    def action_save_agent(self) -> None:
        """Ask for a file name and save the agent (and its settings) there."""
        from tui_gym.ui.file_screen import FileScreen

        title = self.session.game.title
        self.push_screen(
            FileScreen(f"Save the {title} agent", self._suggested_file(), self._save_to,
                       saving=True)
        )

    def action_load_agent(self) -> None:
        """Ask for a file name and load the agent (and its game and settings) from it."""
        from tui_gym.ui.file_screen import FileScreen

        self.push_screen(
            FileScreen("Load an agent", self._suggested_file(loading=True), self._read_file,
                       saving=False),
            self._loaded_file,
        )

    def _suggested_file(self, loading: bool = False) -> str:
        """The name last used for this game, else `<game>-agent.tgym` (when loading,
        only if that file is there)."""
        game = self.session.game.name
        safe = game.replace("/", "-").replace(":", "-")
        path = self._files.get(game, Path.cwd() / f"{safe}-agent.tgym")
        if loading and not path.is_file():
            return ""
        try:
            return str(path.relative_to(Path.cwd()))
        except ValueError:
            return str(path)

    def _save_to(self, path: Path) -> str | None:
        """Save to `path` (the dialog asked before replacing a file); an error or None."""
        was_running = self.runner.running
        self.runner.pause()
        if not self.runner.wait_idle(0):
            return "Training has not handed the agent back yet; try again in a moment."
        try:
            self.session.save(path)
        except StorageError as exc:
            return str(exc)
        except (OSError, ValueError) as exc:
            return f"{path}: cannot write ({exc})"
        finally:
            if was_running:
                self.runner.start()
        self._files[self.session.game.name] = path
        if self.run_log is not None:
            self.run_log.saved(self.session, path)  # the run in the history says where
        episodes = self.session.trainer.episodes
        self.notify(f"Agent saved to {path} ({plural(episodes, 'episode')}).", title="Saved")
        return None

    def _read_file(self, path: Path) -> str | None:
        """Read a save file for `_loaded_file`; an error or None."""
        try:
            self._loaded = (Session.load(path), path)
        except (StorageError, OSError, ValueError) as exc:
            return str(exc)
        return None

    def _loaded_file(self, path: Path | None) -> None:
        """Put a file read by the load dialog in place, asking first when that would
        replace an agent that has trained."""
        loaded, self._loaded = self._loaded, None
        if path is None or loaded is None:
            return
        session, path = loaded
        game = session.game
        current = self._sessions.get(game.name)
        if current is self.session:
            episodes = self._episodes_trained()
        else:
            episodes = current.trainer.episodes if current is not None else 0
        self._ask_first(
            episodes > 0, f"Replace the {game.title} agent?",
            f"The {game.title} agent here has trained {plural(episodes, 'episode')}; "
            f"{path.name} replaces it, its settings and its wrappers.", "Load",
            lambda: self._when_idle(lambda: self._install_now(session, path)),
        )

    def _install_now(self, session: Session, path: Path) -> None:
        if session.game is not self.session.game:
            self.play_view.put_away()
        self._sessions[session.game.name] = session
        self._fresh.discard(session.game.name)
        self._wanted_game = session.game.name
        self._files[session.game.name] = path
        self._use_session(session)
        self.notify(f"Loaded {path}: {session.game.title}, "
                    f"{plural(session.trainer.episodes, 'episode')} trained.", title="Loaded")

    def action_save_screenshot(self) -> None:
        """Save an SVG picture of the screen in the current folder, and say where."""
        self.call_after_refresh(self._save_screenshot)  # once the palette is gone

    def _save_screenshot(self) -> None:
        from tui_gym.core.files import OutputPathError, write_atomically

        stamp = time.strftime("%Y-%m-%dT%H_%M_%S")
        try:
            path = write_atomically(Path.cwd() / f"tui-gym {stamp}.svg", self.export_screenshot())
        except (OutputPathError, OSError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            self.notify(f"Screenshot not saved: {reason}", title="Screenshot", severity="error")
            return
        self.notify(f"Screenshot saved to {path}", title="Screenshot")

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
        noun, recorder = game.game.episode_noun, self.recording.recorder
        when = "" if recorder and recorder.episode_open else f" from the next {noun}"
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
        self._show_session()
        if not (quiet and report.kept_agent):
            self.notify(report.notice, severity="information" if report.kept_agent else "warning",
                        timeout=6)
        if was_running and (report.kept_agent or keep_running):
            self.runner.start()
        return True

    def on_side_panel_algorithm_picked(self, message: SidePanel.AlgorithmPicked) -> None:
        """Another algorithm needs a fresh learner: once it has trained, ask first."""
        from tui_gym.algorithms import algorithm

        cls = algorithm(message.name)
        if cls.name == self.session.algorithm:
            return
        episodes = self._episodes_trained()
        self._ask_first(
            episodes > 0, f"Train with {cls.title} instead?",
            "Another algorithm needs a fresh learner: the agent, trained "
            f"{plural(episodes, 'episode')} with {self.session.learner_class.title}, "
            f"would start over with {cls.title}'s defaults for this game (ctrl+s saves it "
            "first). ε, the learning rate and the other fields change without this.",
            "Switch and reset",
            lambda: self._when_idle(lambda: self._use_algorithm(cls.name),
                                    self.side_panel.reload),
            kept=f"Still {self.session.learner_class.title}: the agent is kept.",
        )

    def _ask_first(
        self, asks: bool, title: str, text: str, yes: str, then: Callable[[], object],
        kept: str = "",
    ) -> None:
        """Run `then` at once unless it `asks` (it would lose a trained agent): then only
        once the person confirms. A no with `kept` puts the side panel back and says it."""
        if not asks:
            then()
            return
        from tui_gym.ui.confirm_screen import ConfirmScreen

        def answer(confirmed: bool | None) -> None:
            if confirmed:
                then()
            elif kept:
                self.side_panel.reload()
                self.notify(kept, timeout=3)

        self.push_screen(ConfirmScreen(title, text, yes), answer)

    def _use_algorithm(self, name: str) -> None:
        self.session.set_algorithm(name)
        self._reload_train()
        self.side_panel.reload()
        cls = self.session.learner_class
        self.notify(f"{cls.title}: a fresh learner with its defaults for "
                    f"{self.session.game.title}. {cls.summary}.", timeout=5)

    def on_side_panel_changed(self, message: SidePanel.Changed) -> None:
        """A new game switches sessions; a change that would reset a trained agent asks."""
        game = game_for(message.env_id)
        if game is not self.session.game:
            self.switch_game(game, otherwise=self.side_panel.reload)
            return
        change: dict[str, Any] = {
            "env_id": message.env_id, "env_kwargs": message.env_kwargs, "choices": message.choices,
        }
        episodes = self._episodes_trained()
        try:
            keeps = not episodes or self.session.rebuild_keeps_agent(**change)
        except ValueError:
            keeps = True  # it cannot be built: `rebuild` says why and changes nothing
        self._ask_first(
            not keeps, "Reset the agent for this change?",
            "It changes what observations mean, so the agent, trained "
            f"{plural(episodes, 'episode')}, would start over (ctrl+s saves it first).",
            "Apply and reset", lambda: self.rebuild(**change),
            kept="Not applied: the agent is kept.",
        )

    # --- help and the command palette ---------------------------------------
    def key_help(self) -> list[tuple[str, list[tuple[str, str]]]]:
        """Every key, grouped by where it works: (section, [(key, what it does)])."""
        from tui_gym.ui.book_view import BookView
        from tui_gym.ui.compare_view import CompareView
        from tui_gym.ui.plan_view import PlanView

        return [
            ("Everywhere", [
                ("p / t / v", "Play view / Train view / Compare view"),
                ("P / f", "Plan view (sweep by sweep) / Book view"),
                *_game_keys(),
                ("w / W", "focus the wrapper panel (W while a board that moves with WASD "
                          "has focus)"),
                ("m", "edit a grid game's map (training or planning)"),
                ("esc", "leave a text field or the side panel: back to the view"),
                ("ctrl+s", "save the agent to a file you name (asks before replacing one)"),
                ("ctrl+o", "load an agent from a file you name"),
                ("? / F1", "this help"),
                ("ctrl+r", "record your games to a file / stop "
                           "(tui-gym replay FILE plays it back)"),
                ("ctrl+p", "command palette (also: screenshot, theme)"),
                ("q", "quit"),
            ]),
            ("Play", self.play_view.key_help()),
            ("Train", [
                ("space", "start / pause training"),
                (".", "run one episode"),
                ("n", "one step (one transition): the step panel explains the update"),
                ("x", "reset the agent (asks first once it has trained)"),
                ("+ / -", "faster / slower (animated ... max)"),
                *self.train_view.key_help(),
            ]),
            ("Compare", CompareView.key_help()),
            ("Plan", PlanView.key_help()),
            ("Book", BookView.key_help()),
            ("Side panel", [
                ("tab / shift+tab", "move between fields"),
                ("space / enter", "tick a wrapper, press a button, pick a game or an "
                                  "algorithm (another algorithm asks first once the agent "
                                  "has trained)"),
                ("enter", "apply a parameter"),
                ("[ / ]", "move the focused wrapper in / out in the chain (first = innermost)"),
                ("esc", "back to the view; an edit not applied with enter is dropped"),
            ]),
            ("Dialogs", [
                ("y / enter", "confirm (enter presses the focused button)"),
                ("n / esc", "cancel"),
            ]),
        ]

    def get_system_commands(self, screen: Screen) -> Iterable[SystemCommand]:
        # Textual's own "Keys" (a second, different key list) and "Screenshot" (saved to
        # a Downloads folder that may not exist, failing without saying why) make way
        # for ours below.
        for command in super().get_system_commands(screen):
            if command.title not in ("Keys", "Screenshot"):
                yield command
        commands: list[tuple[str, str, Callable[[], object]]] = [
            *((f"{label} view", f"{what} ({key})", partial(self.action_show_view, view))
              for view, key, label, what in VIEWS),
            *(
                (f"Game: {g.title}", g.description,
                 lambda name=g.name: self.action_switch_game(name))
                for g in GAMES
            ),
            ("Start / pause training", "Toggle training", self._palette_toggle),
            ("Reset agent", "Empty Q-table, fresh statistics (asks first once trained)",
             self.action_request_reset),
            ("Save agent…", "Save the agent to a file you name (ctrl+s)", self.action_save_agent),
            ("Load agent…", "Load an agent from a file you name (ctrl+o)",
             self.action_load_agent),
            ("Wrappers", "Focus the wrapper panel", self.action_focus_wrappers),
            ("Keys", "Every key tui-gym answers to (? or F1)", self.action_help),
            ("Screenshot", "Save an SVG picture of the screen in the current folder",
             self.action_save_screenshot),
            ("Record games", "Record your games to a file, or stop (ctrl+r)",
             self.action_toggle_recording),
        ]
        yield from (SystemCommand(*command) for command in commands)

    def _palette_toggle(self) -> None:
        if self.current_view != "train":
            self.action_show_view("train")
        self.action_toggle_training()

    async def action_quit(self) -> None:
        self.recording.turn_off()
        if (compare := self.compare_view) is not None:
            compare.stop_comparison()  # it records what finished while the app ends
        self.exit(0)  # the runner closes at unmount, without holding the screen up

    def on_unmount(self) -> None:
        self.recording.turn_off()
        self.runner.close(wait=False)  # `run_app` waits for it once the terminal is back
        if self.run_log is not None:
            self.run_log.close()
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
                loop.add_signal_handler(signum, partial(self.exit, return_code=128 + signum))
            except (RuntimeError, ValueError, NotImplementedError):  # not the main thread
                continue
            self._signals.append(signum)

    def on_terminal_gone(self, message: TerminalGone) -> None:
        """Nobody can see the app or type to it any more: end it, as a hang-up would."""
        self.exit(return_code=128 + signal.SIGHUP)

YOUNG_GC_SECONDS = 0.5  # collect the young generations this often, not right after a key
FULL_GC_SECONDS = 20.0  # and everything this often
GC_SECONDS_ENV = "TUI_GYM_GC_SECONDS"  # "YOUNG,FULL" seconds, to override both


class GcPacer:
    """The collections `tune_gc_for_ui` runs on the app's timers, counted; a young one due
    while a key is answered (`key_since()`, monotonic) waits a turn, once."""

    def __init__(self, key_since: Callable[[], float] = lambda: -KEY_QUIET_SECONDS) -> None:
        self.young_collections = 0
        self.full_collections = 0
        self.young_postponed = 0
        self._key_since = key_since
        self._postponed = False

    # Methods, not `gc.collect` itself: Textual's timers take Python callables only.
    def collect_young(self) -> None:
        if not self._postponed and time.monotonic() - self._key_since() < KEY_QUIET_SECONDS:
            self._postponed = True  # a collection takes milliseconds the key's frame needs
            self.young_postponed += 1
            return
        self._postponed = False
        gc.collect(1)
        self.young_collections += 1

    def collect_all(self) -> None:
        gc.collect()
        self.full_collections += 1


def tune_gc_for_ui(
    app: App[Any], young_seconds: float = YOUNG_GC_SECONDS, full_seconds: float = FULL_GC_SECONDS
) -> GcPacer:
    """Collect garbage on the app's own timers, not mid-frame: what is alive is frozen
    (one app a process), automatic collection off."""
    pacer = GcPacer(lambda: getattr(app, "_key_since", -KEY_QUIET_SECONDS))
    gc.collect()
    gc.freeze()
    gc.disable()
    app.set_interval(young_seconds, pacer.collect_young, name="young-gc")
    app.set_interval(full_seconds, pacer.collect_all, name="full-gc")
    return pacer


def gc_seconds_from_env() -> tuple[float, float] | None:
    """The collection periods set in `TUI_GYM_GC_SECONDS` ("YOUNG,FULL"), or None;
    ValueError when the value is not two positive numbers."""
    text = os.environ.get(GC_SECONDS_ENV, "").strip()
    if not text:
        return None
    with contextlib.suppress(ValueError):
        young, full = (float(part) for part in text.split(","))
        if 0 < young < 1e6 and 0 < full < 1e6:
            return young, full
    raise ValueError(
        f"{GC_SECONDS_ENV} must be two positive numbers of seconds, e.g. 0.5,20; got {text!r}"
    )


EXIT_CRASH = 1


def run_app(
    env_id: str | None = None, seed: int = 0, load: str | None = None, runner: str = "process",
    env_kwargs: dict[str, Any] | None = None,
    *, session: Session | None = None, record: str | None = None,
    replay: Recording | None = None, db: str | None = None, keep_history: bool = True,
) -> int:
    """Open the app (from a saved agent with `load`, or on `session`); returns the exit code.
    The runs trained are kept in the run history (`db`) unless not `keep_history`."""
    gc_seconds = gc_seconds_from_env()
    if session is None:
        session = Session.load(load) if load else Session(env_id=env_id or "", seed=seed,
                                                          env_kwargs=env_kwargs or {})
    run_log = None
    if keep_history:

        def run_log() -> SessionRunLog:  # imported and made after the first frame
            from tui_gym.core.experiments.paths import resolve_db_path
            from tui_gym.session.experiments.app_recording import SessionRunLog

            return SessionRunLog(resolve_db_path(db))

    with history_for_app(db, keep_history) as compare_db:
        return run_standalone(
            TuiGymApp(session, runner=runner, tune_gc=True, gc_seconds=gc_seconds,
                      standalone=True, record=record, replay=replay, run_log=run_log,
                      db=compare_db, history_kept=keep_history)
        )


@contextlib.contextmanager
def history_for_app(db: str | None, keep_history: bool) -> Iterator[str | None]:
    """The Compare view's run history: `db` when runs are kept, else a scratch file gone
    when the app ends (`--no-history`)."""
    if keep_history:
        yield db
        return
    with tempfile.TemporaryDirectory(prefix="tui-gym-") as scratch:
        yield str(Path(scratch) / "runs.db")


def run_standalone(app: TuiGymApp) -> int:
    """Run `app` in this terminal until it ends; returns the exit code (`EXIT_CRASH`
    and one line naming the crash log on an unexpected error, in any thread)."""
    from tui_gym.crash_log import report_crash

    app.standalone = True
    previous_hook = threading.excepthook

    def thread_failed(args: threading.ExceptHookArgs) -> None:
        if terminal_write_failed(args):  # the terminal went away: no crash
            app.post_message(TerminalGone())
        elif args.exc_value is not None and app.thread_crash is None:
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
