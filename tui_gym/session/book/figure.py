"""What a book figure is and what it gives back: `BookFigure`, `FigureOptions`, `FigureResult`."""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap

if TYPE_CHECKING:
    from tui_gym.core.experiments.history import RunHistory

__all__ = ["BookFigure", "Chart", "Check", "FigureOptions", "FigureResult", "FigureStopped",
           "FigureTasks", "Progress", "Series", "book_figure", "heading"]

Progress = Callable[[int, int, str], None]  # (done, total, what is being done)
Measure = Callable[["BookFigure", "FigureOptions", Progress], "FigureResult"]


def heading(name: str) -> str:
    """What a figure is called: "Figure 8.4", or "Example 8.4" for "example 8.4"."""
    return name.capitalize() if name[:1].isalpha() else f"Figure {name}"


class FigureStopped(Exception):
    """A figure's run was stopped before it finished (`FigureOptions.stop`)."""


@dataclass
class FigureTasks:
    """Where a figure's learners run as tasks (`runs.play`): the run history (its runs in
    the figure's first run's `group`), the run to `resume`, the Dask `cluster`; `tasks`
    and `landed` count the tasks and those finished."""

    history: RunHistory | None = None
    resume: int | None = None
    cluster: Any = None
    group: int | None = None
    played: int = 0  # the learners played so far: where the next play's runs start in `group`
    tasks: int = 0
    landed: int = 0


@dataclass(frozen=True)
class FigureOptions:
    """How a figure is run: `runs` and `episodes` (None: the figure's, or with `full` the
    book's), the first `seed`, `stop` (`FigureStopped`) and where `tasks` go."""

    runs: int | None = None
    episodes: int | None = None
    seed: int = 0
    full: bool = False
    stop: threading.Event | None = field(default=None, compare=False)
    tasks: FigureTasks | None = field(default=None, compare=False)

    def check_stop(self, figure: str) -> None:
        """`FigureStopped` once `stop` is set (`figure`: the figure's name)."""
        if self.stop is not None and self.stop.is_set():
            raise FigureStopped(f"{heading(figure)} stopped")


@dataclass(frozen=True, eq=False)
class Series:
    """One curve: `y` over `x`, with its band `lo`..`hi` (the same as `y` when exact)."""

    label: str
    x: npt.NDArray[np.float64]
    y: npt.NDArray[np.float64]
    lo: npt.NDArray[np.float64] | None = None
    hi: npt.NDArray[np.float64] | None = None

    def as_json(self) -> dict[str, Any]:
        lo = self.y if self.lo is None else self.lo
        hi = self.y if self.hi is None else self.hi
        return {"label": self.label, "x": np.asarray(self.x).tolist(),
                "y": np.asarray(self.y).tolist(), "lo": np.asarray(lo).tolist(),
                "hi": np.asarray(hi).tolist()}


@dataclass(frozen=True)
class Chart:
    """Series drawn together (`skip_start`: the y range leaves out the first few points)."""

    title: str
    x_label: str
    series: tuple[Series, ...]
    skip_start: bool = False


@dataclass(frozen=True)
class Check:
    """One of the book's claims: the book's value, the measured one, and whether it holds."""

    claim: str
    book: float | str
    measured: float | str
    ok: bool

    def __post_init__(self) -> None:
        object.__setattr__(self, "ok", bool(self.ok))

    def as_json(self) -> dict[str, Any]:
        return {"claim": self.claim, "book": self.book, "measured": self.measured, "ok": self.ok}


@dataclass(frozen=True)
class FigureResult:
    """A figure as measured: charts and grids to draw, and the checks."""

    figure: str = ""
    title: str = ""
    runs: int = 1
    charts: tuple[Chart, ...] = ()
    panels: tuple[Heatmap, ...] = ()
    checks: tuple[Check, ...] = ()
    notes: tuple[str, ...] = ()

    @property
    def series(self) -> tuple[Series, ...]:
        """Every chart's series, in order."""
        return tuple(s for chart in self.charts for s in chart.series)

    @property
    def ok(self) -> bool:
        return all(check.ok for check in self.checks)

    def as_json(self) -> dict[str, Any]:
        """What `tui-gym book FIGURE --json` prints."""
        return {"figure": self.figure, "title": self.title, "runs": self.runs,
                "series": [s.as_json() for s in self.series],
                "checks": [c.as_json() for c in self.checks]}


@dataclass(frozen=True)
class BookFigure:
    """One of Sutton & Barto's figures, reproduced (see the module docstring)."""

    name: str
    title: str
    about: str
    world: str  # the game it runs on
    run: Callable[[FigureOptions, Progress], FigureResult]
    runs: int | None = None
    episodes: int | None = None
    aliases: Sequence[str] = field(default=())
    full_runs: int | None = None  # the book's counts, where they are more than the defaults
    full_episodes: int | None = None


def book_figure(name: str, world: str, *, title: str, about: str,
                **counts: Any) -> Callable[[Measure], BookFigure]:
    """Make a function that measures a figure the `BookFigure` named `name` on `world`."""

    def make(measure: Measure) -> BookFigure:
        def run(options: FigureOptions, progress: Progress) -> FigureResult:
            return replace(measure(figure, options, progress), figure=name, title=title)

        figure = BookFigure(name, title, about, world, run, **counts)
        return figure

    return make
