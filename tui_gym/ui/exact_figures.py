"""The Train view's figures of a snapshot from the game's exact model, off the event loop.

`compute` gives what the view draws for one snapshot from the exact model: the
heatmap panels (or why there are none), the greedy policy's exact reference with
its note (or a prediction learner's RMS error), and a prediction learner's V
against the exact values. `LatestOnly` runs it on one worker thread at a time:
a request made while one runs replaces the one waiting (never a queue), and a
result reaches the view only while the view still shows the generation it was
asked in (`drop` starts a new one: a reset, a rebuild, another game or algorithm).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from textual.message import Message
from textual.widget import Widget

if TYPE_CHECKING:
    from tui_gym.core.engine.stats import TrainingSnapshot
    from tui_gym.core.heatmap import Heatmap
    from tui_gym.games.base import ReferenceMetrics
    from tui_gym.session.prediction import PredictionFigures
    from tui_gym.session.session import Session

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


class LatestOnly:
    """Computes `Figures` for a widget on one worker thread at a time, the latest request
    winning; each result comes back to the widget as a `Computed` message."""

    class Computed(Message):
        """The figures of a request (or the error computing them), on the event loop."""

        def __init__(self, generation: int, figures: Figures | None,
                     error: BaseException | None) -> None:
            super().__init__()
            self.generation = generation
            self.figures = figures
            self.error = error

    def __init__(self, widget: Widget) -> None:
        self.widget = widget
        self.generation = 0
        self._running = False
        self._waiting: Request | None = None

    @property
    def idle(self) -> bool:
        """Nothing computing, nothing waiting."""
        return not self._running and self._waiting is None

    def ask(self, request: Request) -> None:
        """Compute `request` now, or when the one running ends (replacing one waiting)."""
        if self._running:
            self._waiting = request
            return
        self._running = True
        generation = self.generation
        self.widget.run_worker(lambda: self._work(generation, request), thread=True,
                               group="exact-figures", exit_on_error=False)

    def drop(self) -> None:
        """What is computing or waiting belongs to what was shown before: never show it."""
        self.generation += 1
        self._waiting = None

    def _work(self, generation: int, request: Request) -> None:
        try:
            figures, error = compute(request), None
        except Exception as exc:  # noqa: BLE001  (raised on the event loop if still wanted)
            figures, error = None, exc
        self.widget.post_message(self.Computed(generation, figures, error))

    def done(self, message: Computed) -> Figures | None:
        """The message's figures when they are still wanted (ask the next one waiting);
        an error computing wanted figures is raised here, on the event loop."""
        self._running = False
        waiting, self._waiting = self._waiting, None
        if waiting is not None:
            self.ask(waiting)
        if message.generation != self.generation:
            return None
        if message.error is not None:
            raise message.error
        return message.figures
