"""The Compare view: the game's recorded runs side by side, and comparisons launched here."""

from __future__ import annotations

import time
from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, VerticalScroll
from textual.strip import Strip
from textual.widgets import Button, Input, Label, SelectionList
from textual.widgets.selection_list import Selection

from tui_gym.core.experiments import (
    DamagedRun,
    DamagedRunError,
    RunHistory,
    RunHistoryError,
    RunRecord,
    RunSummary,
    resolve_db_path,
)
from tui_gym.core.experiments.connection import examine
from tui_gym.core.params import digits_note, read_number, shown_value
from tui_gym.core.text import visible
from tui_gym.games.words import plural
from tui_gym.ui.compare_job import CompareJob
from tui_gym.ui.compare_series import (
    FigureRow,
    Series,
    algorithm_title,
    bounded,
    row_of_outcome,
    row_of_record,
    run_label,
    series_of_outcome,
    series_of_record,
)
from tui_gym.ui.map_editing import SessionView
from tui_gym.ui.textual_internals import ticked_line
from tui_gym.ui.widgets.compare_chart import PALETTE, CompareChart
from tui_gym.ui.widgets.figures_table import FiguresTable, with_interval
from tui_gym.ui.widgets.numbers import compact_count
from tui_gym.ui.widgets.progress_line import ProgressLine
from tui_gym.ui.widgets.stats_panel import format_duration
from tui_gym.ui.widgets.text_field import TextField
from tui_gym.ui.widgets.tick_box import TickBox

if TYPE_CHECKING:
    from tui_gym.session.experiments.compare import AlgorithmOutcome, CompareSpec
    from tui_gym.session.session import Session

POLL_SECONDS = 0.25  # how often the view looks at a running comparison
LISTED_RUNS = 200  # the newest runs of the game that the list offers
OPEN_TIMEOUT = 2.0  # seconds the view waits on a history another process is writing
MAX_SEEDS = 1_000
MAX_EPISODES = 10_000_000
# A comparison keeps every seed's per-episode returns in memory until it ends.
MAX_SEED_EPISODES = 20_000_000
DEFAULT_SEEDS = 10
DEFAULT_ALGORITHMS = ("q-learning", "sarsa")


def parse_count(text: str, what: str, high: int) -> int:
    """A whole number from 1 to `high` typed in a field (digits 0-9, `,` or `_` between
    them); ValueError saying what is wanted."""
    value = read_number(text.strip().replace(",", ""))
    if value is None or not 1 <= value <= high or value % 1:
        shown = shown_value(text.strip()) if text.strip() else "nothing"
        digits = ", in digits 0-9" if digits_note(text) else ""
        raise ValueError(f"{what}: a whole number from 1 to {high:,}{digits} (got {shown})")
    return int(value)


@dataclass(frozen=True)
class Launch:
    """What the launch form asks for: algorithms (registry names), seeds, episodes."""

    algorithms: tuple[str, ...]
    seeds: int
    episodes: int


def read_launch(algorithms: Sequence[str], seeds: str, episodes: str) -> Launch:
    """The form's values checked; ValueError naming every wrong field, one line."""
    problems = []
    if not algorithms:
        problems.append("tick at least one algorithm")
    counts = []
    for text, what, high in ((seeds, "Seeds", MAX_SEEDS), (episodes, "Episodes", MAX_EPISODES)):
        try:
            counts.append(parse_count(text, what, high))
        except ValueError as exc:
            problems.append(str(exc))
    if not problems and counts[0] * counts[1] > MAX_SEED_EPISODES:
        problems.append(
            f"seeds × episodes is at most {MAX_SEED_EPISODES:,} (every seed's returns are "
            f"kept until the end; got {counts[0] * counts[1]:,})"
        )
    if problems:
        raise ValueError("; ".join(problems))
    return Launch(tuple(algorithms), counts[0], counts[1])


def edited_settings(session: Session, algorithms: Sequence[str]) -> dict[str, Any]:
    """The Train view's hyperparameters that differ from the game's defaults and one of
    `algorithms` has (the episode budget aside: the launch form sets it)."""
    from tui_gym.algorithms import algorithm
    from tui_gym.session.session import default_settings

    hp = session.hp
    if hp is None:
        return {}
    defaults = default_settings(session.game, session.algorithm, session.env_kwargs)
    owned = {f.name for name in algorithms for f in algorithm(name).params}
    return {
        name: value for name, value in hp.items()
        if name != "episodes" and name in owned and defaults.get(name) != value
    }


class RunList(SelectionList[int]):
    """The runs, one a line, each with a tick box that reads ✓ when ticked."""

    DEFAULT_CSS = """
    RunList { height: auto; max-height: 10; border: none; padding: 0; }
    RunList:focus { border: none; }
    """

    def render_line(self, y: int) -> Strip:
        # Textual's box draws the same X on and off; say the state with the mark itself.
        return ticked_line(
            super().render_line(y),
            lambda: self.get_option_at_index(self.scroll_offset.y + y).value in self.selected,
        )


def describe_run(run: RunSummary) -> Text:
    """A run's line in the list: label, kind, seeds, final return, status unless finished,
    and when it started."""
    from datetime import datetime

    when = datetime.fromtimestamp(run.started_at).strftime("%m-%d %H:%M")
    parts = [run_label(run), str(run.kind), plural(len(run.seeds), "seed")]
    figure = run.figure("mean_return_last")
    if figure is not None:
        parts.append(f"return {with_interval(figure)}")
    if str(run.status) == "running" and str(run.kind) == "app":
        parts.append("open in the app")  # it ends when the app lets the agent go
    elif str(run.status) != "finished":
        resumes = str(run.kind) == "compare" and str(run.status) != "running"
        parts.append(f"{run.status}{', c resumes' if resumes else ''}")
    parts.append(when)
    return Text(" · ".join(parts), no_wrap=True, overflow="ellipsis")


def _unreadable(damaged: Sequence[DamagedRun]) -> str:
    """One line naming the runs of the history that do not read."""
    if len(damaged) == 1:
        bad = damaged[0]
        return (f"Run {bad.id} cannot be read: {visible(bad.reason, 120)} "
                f"(`tui-gym runs rm {bad.id}` removes it); the other runs are listed.")
    ids = ", ".join(str(d.id) for d in damaged[:10]) + (", ..." if len(damaged) > 10 else "")
    return (f"{len(damaged):,} runs cannot be read ({ids}): `tui-gym runs show ID` says why, "
            "`tui-gym runs rm ID` removes one; the other runs are listed.")


class CompareView(SessionView):
    """Runs of the current game, their curves and figures, and comparisons to launch."""

    SCOPED_CSS = False  # the compact rules start at Screen
    DEFAULT_CSS = """
    CompareView #compare-algorithms { layout: grid; grid-size: 3; grid-gutter: 0 1; height: auto; }
    CompareView #compare-algorithms TickBox { width: 1fr; }
    CompareView #compare-fields { height: 1; }
    CompareView #compare-fields Label { padding: 0 1 0 0; color: $text-muted; }
    CompareView #compare-fields Input { width: 10; margin-right: 2; }
    CompareView #compare-fields Input.-invalid { border: none; color: $text-error; }
    CompareView #compare-fields Button { min-width: 0; margin-right: 1; }
    CompareView #compare-progress { display: none; }
    CompareView #compare-progress.-running { display: block; }
    CompareView #compare-message { width: 1fr; color: $text-muted; text-wrap: wrap; height: auto; }
    CompareView #compare-message.-error { color: $text-error; }
    CompareView #compare-runs-title { color: $text-muted; text-style: bold; margin-top: 1; }
    CompareView #compare-chart { margin-top: 1; }

    Screen.compact CompareView { padding: 0; }
    Screen.compact CompareView #compare-runs-title { margin-top: 0; }
    Screen.compact CompareView #compare-chart { margin-top: 0; }
    Screen.compact CompareView RunList { max-height: 5; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("l", "launch", "Launch", tooltip="Run a comparison with the chosen algorithms"),
        Binding("s", "stop", "Stop", tooltip="Stop the comparison; what finished is kept"),
        Binding("c", "resume", "Resume", tooltip="Carry on the highlighted unfinished "
                "comparison: only its missing tasks run"),
        Binding("o", "toggle_smoothing", "Smooth", tooltip="Smoothed curves, or as recorded"),
        Binding("r", "reload", "Reload", tooltip="Read the run history again"),
        Binding("escape", "focus_list", "Back to the runs", show=False),
    ]

    def __init__(
        self, *, db: str | Path | None = None, kept: bool = True, processes: int | None = None,
        id: str | None = None, classes: str | None = None,
    ) -> None:
        """`db`: the run history (None: the default file; `kept` False: a scratch file);
        `processes`: `run_compare`'s."""
        super().__init__(id=id, classes=classes)
        self.db = db  # read at each look, so the app can point the view elsewhere
        self.kept = kept
        self.processes = processes
        self.runs: tuple[RunSummary, ...] = ()  # the game's runs the list offers, newest first
        self._records: dict[int, RunRecord] = {}
        self._colours: dict[Hashable, int] = {}
        self.history_error: str | None = None
        self._game_key: frozenset[str] = frozenset()
        self.job: CompareJob | None = None
        self._job_game: frozenset[str] = frozenset()
        self._seen_progress = -1
        self._live_outcomes: tuple[AlgorithmOutcome, ...] = ()
        self.smooth = True  # curves drawn through a trailing mean (o toggles)
        self.message = ""  # the line under the form: an error, the job's state
        self._stale = True  # the list has not been read for the current game

    @property
    def db_path(self) -> Path:
        return resolve_db_path(None if self.db is None else str(self.db))

    # --- layout ------------------------------------------------------------------
    def compose(self) -> ComposeResult:
        from tui_gym.algorithms import ALGORITHMS

        # The parts the view updates, kept at hand: a timer tick never searches the DOM.
        self._boxes = {
            cls.name: TickBox(cls.title, value=cls.name in DEFAULT_ALGORITHMS, compact=True,
                              id=f"algo-{cls.name}", tooltip=cls.summary)
            for cls in ALGORITHMS
        }
        self._seeds = TextField(str(DEFAULT_SEEDS), id="compare-seeds", compact=True,
                            tooltip=f"independent learners per algorithm, 1 to {MAX_SEEDS:,}")
        self._episodes = TextField("", id="compare-episodes", compact=True,
                               tooltip=f"episodes each learner trains, 1 to {MAX_EPISODES:,}")
        self._launch = Button("▶ Compare", id="btn-compare", variant="success", compact=True,
                              tooltip="Run the comparison for this game and its settings (l)")
        self._stop = Button("■ Stop", id="btn-stop", variant="error", compact=True,
                            disabled=True, tooltip="Stop it; what finished is recorded (s)")
        self._progress = ProgressLine(id="compare-progress")
        self._message_label = Label("", id="compare-message", markup=False)
        self.run_list = RunList(id="compare-runs")
        self.chart = CompareChart(id="compare-chart")
        self.table = FiguresTable(id="compare-table")

        with Horizontal(id="compare-algorithms"):
            yield from self._boxes.values()
        with Horizontal(id="compare-fields"):
            yield Label("Seeds")
            yield self._seeds
            yield Label("Episodes")
            yield self._episodes
            yield self._launch
            yield self._stop
        yield self._progress
        yield self._message_label
        with VerticalScroll(id="compare-body"):
            yield Label("Runs of this game (space ticks a run)", id="compare-runs-title")
            yield self.run_list
            yield self.chart
            yield self.table

    def on_mount(self) -> None:
        self.set_interval(POLL_SECONDS, self._poll)
        self.reload()
        if self.display:
            self.focus_default()

    @property
    def running(self) -> bool:
        return self.job is not None and self.job.running

    def _say(self, text: str, error: bool = False) -> None:
        self.message = text
        label = self._message_label
        label.update(text)
        label.set_class(error, "-error")

    # --- what the app calls ------------------------------------------------------
    def reload(self, fresh: bool = False) -> None:
        """Follow the session's game (after a switch, a load); `fresh` reads the history
        again (when the view is shown). The history is only read while the view shows."""
        if fresh:
            self._stale = True
        game = self.session.game  # the names a run of the game may be recorded under
        key = frozenset(n.casefold() for n in (game.name, game.env_id, *game.other_ids) if n)
        if key != self._game_key:
            self._game_key = key
            self.stop_comparison()  # a comparison belongs to the game it was launched for
            self._records.clear()
            self._colours.clear()
            hp = self.session.hp
            budget = hp.get("episodes") if hp is not None else None
            self._episodes.value = str(budget or "")
            self._stale = True
        if self._stale and self.display:  # the history is read when the view is shown
            self.action_reload()

    def focus_default(self) -> None:
        self.run_list.focus()

    def stop_comparison(self) -> bool:
        """Ask a running comparison to stop (it records what finished); whether one ran."""
        job = self.job
        if job is None or not job.running or job.stop_event.is_set():
            return False
        job.stop()
        self._say("Stopping: the episodes every seed has finished are kept and recorded.")
        return True

    @staticmethod
    def key_help() -> list[tuple[str, str]]:
        """(key, what it does) in this view."""
        return [
            ("↑ ↓ / space", "move in the list of runs / tick a run to draw it"),
            ("tab / shift+tab", "the algorithms, Seeds, Episodes and the buttons"),
            ("l / enter", "run the comparison (enter in Seeds or Episodes)"),
            ("s", "stop the comparison; what finished is recorded"),
            ("c", "resume the highlighted unfinished comparison: only its missing tasks run"),
            ("o", "smoothed curves (a trailing mean over a tenth of each) / as recorded"),
            ("r", "read the run history again (runs recorded elsewhere)"),
            ("esc", "leave a field or a button: back to the list of runs"),
        ]

    # --- the history ---------------------------------------------------------------
    def _open(self) -> RunHistory | None:
        """The history, or None when there is none yet; RunHistoryError when it cannot open."""
        path = self.db_path
        status = examine(path)
        if status is None or status.st_size == 0:
            return None  # reading never creates the file
        return RunHistory(path, timeout=OPEN_TIMEOUT, read_only=True)

    def action_reload(self, select: Sequence[int] = ()) -> None:
        """Read the game's runs from the history again (`select`: runs to tick as well)."""
        self._stale = False
        names = self._game_key
        damaged: dict[int, DamagedRun] = {}
        try:
            history = self._open()
            if history is None:
                runs: list[RunSummary] = []
            else:
                found: dict[int, RunSummary] = {}
                with history:
                    for name in sorted(names):
                        read = history.read_runs(game=name, limit=LISTED_RUNS)
                        found.update((r.id, r) for r in read.runs)
                        damaged.update((d.id, d) for d in read.damaged)
                runs = sorted(found.values(), key=lambda r: (-r.started_at, -r.id))[:LISTED_RUNS]
        except (RunHistoryError, OSError) as exc:
            self.history_error = str(exc)
            self.runs = ()
            self._records.clear()
            self._fill_list(())
            self._say(f"The run history cannot be read: {exc}", error=True)
            self._redraw()
            return
        self.history_error = None
        self.runs = tuple(runs)
        known = {r.id for r in runs}
        ticked = [i for i in self.run_list.selected if i in known]
        ticked += [i for i in select if i in known and i not in ticked]
        for run_id in [i for i in self._records if i not in known or i in select]:
            del self._records[run_id]  # gone, or rewritten since it was read
        self._fill_list(ticked)
        if not self.running:
            title = self.session.game.title
            if not runs and not self.kept:
                self._say(f"No comparisons of {title} yet (--no-history: they are shown "
                          "until the app ends, and not kept): choose algorithms, seeds and "
                          "episodes, then Compare.")
            elif not runs:
                self._say(f"No runs of {title} recorded yet in {self.db_path}: "
                          "choose algorithms, seeds and episodes, then Compare.")
            else:
                self._say(f"{plural(len(runs), 'run')} of {title} recorded.")
            if damaged:
                self._say(_unreadable(list(damaged.values())), error=True)
        self._message_label.tooltip = (
            str(self.db_path) if self.kept else "not kept: the app runs with --no-history")
        self._redraw()

    def _fill_list(self, ticked: Sequence[int]) -> None:
        run_list = self.run_list
        highlighted = run_list.highlighted
        run_list.clear_options()
        run_list.add_options(
            Selection(describe_run(run), run.id, run.id in ticked) for run in self.runs
        )
        if self.runs:
            run_list.highlighted = min(highlighted or 0, len(self.runs) - 1)

    def _record(self, run_id: int) -> RunRecord | None:
        record = self._records.get(run_id)
        if record is not None:
            return record
        try:
            history = self._open()
            if history is None:
                return None
            with history:
                record = history.get_run(run_id)
        except DamagedRunError as exc:
            self._say(f"{str(exc)[:1].upper()}{str(exc)[1:]}", error=True)
            return None
        except (RunHistoryError, OSError) as exc:
            self._say(f"Run {run_id} cannot be read: {exc}", error=True)
            return None
        self._records[run_id] = record
        return record

    # --- drawing -------------------------------------------------------------------
    def _colour_for(self, key: Hashable, shown: set[Hashable]) -> int:
        if key in self._colours:
            return self._colours[key]
        used = {self._colours[k] for k in shown if k in self._colours}
        place = next((i for i in range(len(PALETTE)) if i not in used), len(self._colours))
        self._colours[key] = place
        return place

    def _redraw(self) -> None:
        from tui_gym.session.returns import return_range_of

        game, env_id = self.session.game, self.session.env_id  # the returns the game allows
        entries: list[tuple[Series | None, FigureRow, Hashable]] = []
        for run_id in self.run_list.selected:
            record = self._record(run_id)
            if record is not None:
                series = series_of_record(record, self.smooth)
                if series is not None:
                    series = bounded(series, return_range_of(
                        game, env_id, record.game_params,
                        ((w.name, w.params) for w in record.wrappers)))
                entries.append((series, row_of_record(record), run_id))
        job = self.job
        live_allowed = None if job is None or not self._live_outcomes else return_range_of(
            game, env_id, job.spec.game_params,
            ((c.name, c.values()) for c in job.spec.wrappers))
        for outcome in self._live_outcomes:
            title = algorithm_title(outcome.algorithm)
            series = series_of_outcome(outcome, f"{title} (live)", self.smooth)
            if series is not None:
                entries.append((bounded(series, live_allowed), row_of_outcome(outcome, title),
                                series.key))
        shown = {key for _, _, key in entries}
        for key in [k for k in self._colours if k not in shown]:
            del self._colours[key]
        colours = [self._colour_for(key, shown) for _, _, key in entries]
        curves = [(s, c) for (s, _, _), c in zip(entries, colours, strict=True) if s is not None]
        self.chart.show([s for s, _ in curves], [c for _, c in curves])
        self.table.show([row for _, row, _ in entries], colours)

    # --- launching -----------------------------------------------------------------
    def action_launch(self) -> None:
        if self.running:
            self._say("A comparison is running: stop it first (s).", error=True)
            return
        if self.history_error is not None:
            self._say(f"Not started: the run history cannot be read ({self.history_error}).",
                      error=True)
            return
        chosen = [name for name, box in self._boxes.items() if box.value]
        try:
            launch = read_launch(chosen, self._seeds.value, self._episodes.value)
        except ValueError as exc:
            self._say(f"Not started: {exc}.", error=True)
            return
        try:
            spec = self._spec(launch)
        except ValueError as exc:
            self._say(f"Not started: {exc}", error=True)
            return
        self.start_job(CompareJob(spec, self.db_path, processes=self.processes))

    def _spec(self, launch: Launch, first_seed: int | None = None) -> CompareSpec:
        from tui_gym.session.experiments.compare import CompareSpec

        session = self.session
        return CompareSpec(
            game=session.env_id, algorithms=launch.algorithms, seeds=launch.seeds,
            episodes=launch.episodes, settings=edited_settings(session, launch.algorithms),
            game_params=dict(session.env_kwargs), wrappers=tuple(session.choices),
            first_seed=session.seed if first_seed is None else first_seed,
        )

    def action_resume(self) -> None:
        """Carry on the highlighted run's comparison, with the settings as they are now (the
        comparison refuses if they are not the run's)."""
        index = self.run_list.highlighted
        if self.history_error is not None or index is None or index >= len(self.runs):
            self._say("Not resumed: highlight an unfinished comparison in the list of runs.",
                      error=True)
            return
        try:
            head, launch, first_seed = self._resumable(self.runs[index])
            spec = self._spec(launch, first_seed)
        except (ValueError, RunHistoryError, OSError) as exc:
            self._say(f"Not resumed: {exc}", error=True)
            return
        self.start_job(CompareJob(spec, self.db_path, processes=self.processes, resume=head))

    def _resumable(self, run: RunSummary) -> tuple[int, Launch, int]:
        """The first run of `run`'s comparison, and its algorithms, seeds and episodes, and
        first seed; ValueError saying why it cannot be resumed."""
        head = run.id if run.group is None else run.group
        history = self._open()
        if history is None:
            raise ValueError("the run history is gone")
        with history:
            records = [history.get_run(i) for i in history.group_ids(head)]
        first = records[0]
        if str(first.summary.kind) != "compare":
            raise ValueError(f"run {head} is a {first.summary.kind} run: only a comparison "
                             "resumes here")
        statuses = {str(r.summary.status) for r in records}
        if "running" in statuses:
            raise ValueError(f"run {head}'s comparison is still running in another process")
        if statuses == {"finished"}:
            raise ValueError(f"run {head}'s comparison finished: nothing is missing")
        seeds, episodes = first.summary.seeds, first.hyperparameters.get("episodes")
        if not seeds or list(seeds) != list(range(seeds[0], seeds[0] + len(seeds))) or not (
                isinstance(episodes, int) and episodes >= 1):
            raise ValueError(f"run {head} does not say its seeds and episodes as a comparison "
                             "does")
        algorithms = tuple(r.summary.algorithm for r in records)
        if len(set(algorithms)) < len(algorithms) or any(
                r.summary.seeds != seeds or r.hyperparameters.get("episodes") != episodes
                for r in records):  # a book figure's runs, say: not one comparison
            raise ValueError(f"run {head}'s runs are not one comparison of learners: resume "
                             f"them with the command that started them (--resume {head})")
        return head, Launch(algorithms, len(seeds), episodes), seeds[0]

    def start_job(self, job: CompareJob) -> None:
        """Run `job` and follow it."""
        self.job = job
        self._job_game = self._game_key
        self._seen_progress = -1
        self._live_outcomes = ()
        job.start()
        self._show_running(True)
        spec = job.spec
        names = ", ".join(algorithm_title(a) for a in spec.algorithms)
        settings = ", ".join(f"{k}={v}" for k, v in spec.settings.items())
        doing = "Comparing" if job.resume is None else f"Resuming run #{job.resume}:"
        self._say(f"{doing} {names}: {spec.seeds:,} seeds × {compact_count(spec.episodes)} "
                  f"episodes" + (f", with {settings} from the Train view" if settings else "")
                  + "…")
        self._progress.show(0, 1)

    def _show_running(self, running: bool) -> None:
        """The progress line, the buttons and the keys of a running comparison, or not."""
        self._progress.set_class(running, "-running")
        self._stop.disabled = not running
        self._launch.disabled = running
        self.refresh_bindings()

    def action_stop(self) -> None:
        if not self.stop_comparison():
            self._say("No comparison is running.")

    def action_focus_list(self) -> None:
        """Leave a field or a button: the keys go to the list of runs again."""
        self.focus_default()

    def action_toggle_smoothing(self) -> None:
        self.smooth = not self.smooth
        self._redraw()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "stop":
            return self.running
        if action in ("launch", "resume"):
            return not self.running
        return True

    # --- following a comparison ------------------------------------------------------
    def _poll(self) -> None:
        job = self.job
        if job is None:
            return
        progress = job.progress
        if job.progress_count != self._seen_progress and progress is not None:
            self._seen_progress = job.progress_count
            done, total = int(progress.done), max(1, int(progress.total))
            elapsed = max(1e-9, time.monotonic() - job.started_at)
            eta = format_duration(elapsed / done * (total - done)) if 0 < done < total else ""
            self._progress.show(done, total, eta)
            self._live_outcomes = job.outcomes
            self._redraw()
        if job.done:
            self._finished(job)

    def _finished(self, job: CompareJob) -> None:
        self.job = None
        self._show_running(False)
        result = job.result
        self._live_outcomes = ()
        if job.error is not None or result is None:
            self._say(job.error or "The comparison ended without a result.", error=True)
            self._redraw()
            return
        run_ids = [o.run_id for o in result.outcomes if o.run_id is not None]
        # The recorded runs take over the live curves' colours.
        for outcome in result.outcomes:
            live_colour = self._colours.pop(("live", outcome.algorithm), None)
            if live_colour is not None and outcome.run_id is not None:
                self._colours[outcome.run_id] = live_colour
        if self._job_game == self._game_key:
            self.action_reload(select=run_ids)
        seconds = format_duration(time.monotonic() - job.started_at)
        how = "stopped" if result.interrupted else "finished"
        recorded = (f"recorded as run{'s' * (len(run_ids) != 1)} "
                    + ", ".join(f"#{i}" for i in run_ids) if run_ids else "nothing was recorded")
        self._say(f"Comparison {how} in {seconds}: {recorded}.")
        self.app.notify(f"Comparison {how}: {recorded}.", title="Compare", timeout=5)

    # --- events ------------------------------------------------------------------
    @on(SelectionList.SelectedChanged)
    def _ticked(self, event: SelectionList.SelectedChanged) -> None:
        event.stop()
        self._redraw()

    @on(Button.Pressed)
    def _button(self, event: Button.Pressed) -> None:
        event.stop()
        if event.button.id == "btn-compare":
            self.action_launch()
        elif event.button.id == "btn-stop":
            self.action_stop()

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.action_launch()

    def on_unmount(self) -> None:
        if self.job is not None:  # stopped, and waited for (bounded) to record what finished
            self.job.close()


__all__ = ["CompareView", "Launch", "RunList", "parse_count", "read_launch"]
