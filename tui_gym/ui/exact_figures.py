"""The views' figures from the game's exact model, computed off the event loop.

`compute` gives what the Train view draws for one snapshot; `LatestOnly` runs such work
on a worker thread, the latest request winning and a stale result dropped.
"""

from __future__ import annotations

import dataclasses
import re
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from textual.message import Message
from textual.widget import Widget

from tui_gym.ui.textual_internals import watch_frames

if TYPE_CHECKING:
    from tui_gym.core.engine.stats import TrainingSnapshot
    from tui_gym.core.heatmap import Heatmap
    from tui_gym.games.base import ReferenceMetrics
    from tui_gym.session.session import PredictionFigures, Session

KEY_QUIET_SECONDS = 0.15  # after a key is handed on, its frame comes before any figures
KEY_FRAME_PATIENCE = 0.5  # seconds; and the figures wait for its frame at most this long
HOLD_STEP = 0.01  # seconds between two looks while held
MAX_REST = 0.5  # seconds; the longest rest after one computation

Asked = TypeVar("Asked")
Result = TypeVar("Result")

# How the layouts' words for values read for traces: "max Q and the greedy move" is then
# "max e and the most eligible move", and no `*` marks a move that is not optimal.
TRACE_WORDS = (
    (re.compile(r"\bQ(-values)?\b"), "e"),
    (re.compile(r"\bgreedy\b"), "most eligible"),
    (re.compile(r"\s+\* [^,]*$|,? n\* [^,]*"), ""),
)


@dataclass(frozen=True)
class Request:
    """What the figures are asked of: a detached session (`Session.detached`), the
    snapshot, what the heatmaps follow and whether they show the traces."""

    session: Session
    snapshot: TrainingSnapshot
    focus: Any
    traces: bool


@dataclass(frozen=True)
class Figures:
    """The exact figures of one request, as the view draws them."""

    request: Request
    panels: list[Heatmap] | None  # None: no per-state view (`hidden` says why)
    hidden: str
    reference: ReferenceMetrics | None
    note: str  # beside the reference in the stats panel
    prediction: PredictionFigures | None  # a prediction learner's, when it has them
    prediction_reason: str


def compute(request: Request) -> Figures:
    """The figures of `request` (on a worker thread: it reads only the detached session)."""
    session, snapshot = request.session, request.snapshot
    panels = session.heatmaps(snapshot, focus=request.focus, traces=request.traces)
    hidden = "" if panels is not None else (
        session.hidden_reason() or "No per-state view of this table.")
    reference, prediction, reason = None, None, ""
    if session.predicts:  # its figure is V's error, not a greedy policy's gap
        prediction = session.prediction(snapshot)
        reason = session.prediction_reason() if prediction is None else ""
        note = (f"RMS error of V {prediction.rms:.4f} against the exact values of the "
                "policy it follows" if prediction is not None else f"no RMS error: {reason}")
    else:
        reference = session.reference(snapshot)
        if reference is None:
            note = session.exact_reason()
        else:  # at the budget's end: why it ends short of the bound, if it does
            note = session.shortfall(reference) if snapshot.episodes >= snapshot.budget else ""
    if request.traces and panels is not None:
        panels = [traced(panel) for panel in panels]
    return Figures(request, panels, hidden, reference, note, prediction, reason)


def traced(panel: Heatmap) -> Heatmap:
    """A heatmap panel drawn from the traces, its title and legend saying so."""

    def say(text: str) -> str:
        for pattern, word in TRACE_WORDS:
            text = pattern.sub(word, text)
        return text

    return dataclasses.replace(panel, title=say(panel.title), legend=say(panel.legend))


# The one lock every `LatestOnly` computes under, and when (`time.monotonic()`) the next may start.
TURNS = SimpleNamespace(lock=threading.Lock(), rest_until=0.0)


class LatestOnly(Generic[Asked, Result]):
    """Runs `work` for a widget on a worker thread, the latest request winning, as a
    `Computed` message. All take turns on one lock, none while a key is answered
    (`key_wait`), each resting as long as the last took on the CPU."""

    class Computed(Message):
        """The result of a request (or the error computing it), on the event loop."""

        def __init__(self, owner: LatestOnly[Any, Any], generation: int, result: Any,
                     error: BaseException | None) -> None:
            super().__init__()
            self.owner = owner
            self.generation = generation
            self.result = result
            self.error = error

    def __init__(self, widget: Widget, work: Callable[[Asked], Result],
                 key_wait: Callable[[], float] | None = None) -> None:
        self.widget = widget
        self.work = work
        self.key_wait = key_wait or (lambda: key_wait_of(self._app))
        self._app: Any = None  # the widget's, read on the worker thread
        self.generation = 0
        self.held = False  # the worker waits: a key being answered, or its rest
        self._running = False
        self._waiting: tuple[int, Asked] | None = None
        self._lock = threading.Lock()  # `_waiting` and `generation`, read by the worker

    @property
    def idle(self) -> bool:
        """Nothing computing, nothing waiting."""
        return not self._running and self._waiting is None

    def ask(self, request: Asked) -> None:
        """Compute `request` when the worker comes to it (replacing one waiting)."""
        self._app = self.widget.app
        watch_drawing(self._app)
        with self._lock:
            self._waiting = (self.generation, request)
        if not self._running:
            self._start()

    def _start(self) -> None:
        self._running = True
        self.widget.run_worker(self._work, thread=True, group="exact-figures",
                               exit_on_error=False)

    def drop(self) -> None:
        """What is computing or waiting belongs to what was shown before: never show it."""
        with self._lock:
            self.generation += 1
            self._waiting = None

    def _hold(self, until: float = 0.0) -> None:
        """Wait (on the worker thread) until `until` and while a key is answered."""
        while True:
            wait = max(until - time.monotonic(), self.key_wait())
            if wait <= 0:
                self.held = False
                return
            self.held = True
            time.sleep(min(wait, HOLD_STEP))

    def _work(self) -> None:
        self._hold(TURNS.rest_until)
        with TURNS.lock:
            with self._lock:
                waiting, self._waiting = self._waiting, None
            generation, result, error = self.generation, None, None
            if waiting is not None:
                generation, request = waiting
                began = time.thread_time()
                try:
                    result = self.work(request)
                except Exception as exc:  # noqa: BLE001  (raised on the event loop if wanted)
                    error = exc
                TURNS.rest_until = time.monotonic() + min(MAX_REST, time.thread_time() - began)
        self._hold()
        self.widget.post_message(self.Computed(self, generation, result, error))

    def done(self, message: Computed) -> Result | None:
        """The message's result when it is still wanted (ask the next one waiting);
        an error computing a wanted result is raised here, on the event loop."""
        self._running = False
        if self._waiting is not None:
            self._start()
        if message.generation != self.generation:
            return None
        if message.error is not None:
            raise message.error
        return message.result  # type: ignore[no-any-return]


def key_wait_of(app: Any) -> float:
    """Seconds until the key the app handed on last has been drawn (`KEY_QUIET_SECONDS`
    after it, and a frame drawn since); 0 or less: none is being answered."""
    since = getattr(app, "_key_since", None)
    if not isinstance(since, float) or since <= 0:
        return 0.0
    now = time.monotonic()
    wait = since + KEY_QUIET_SECONDS - now
    drawn = _DRAWN.get(app)
    if drawn is not None and drawn[0] < since:  # the key's frame is still to come
        wait = max(wait, min(HOLD_STEP, since + KEY_FRAME_PATIENCE - now))
    return wait


_DRAWN: weakref.WeakKeyDictionary[Any, list[float]] = weakref.WeakKeyDictionary()


def watch_drawing(app: Any) -> None:
    """Keep when `app` last drew a frame, for `key_wait_of` (once per app, on its event
    loop; nothing kept where this Textual's frames cannot be watched)."""
    if app is None or app in _DRAWN:
        return
    drawn = [0.0]

    def on_frame(renderable: Any) -> None:
        drawn[0] = time.monotonic()

    if watch_frames(app, on_frame):
        _DRAWN[app] = drawn
