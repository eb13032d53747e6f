"""The `compare` and `sweep` commands: learners across seeds, and settings across a grid."""

from __future__ import annotations

import argparse
import os
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any, TypeVar

from rich.console import Console
from rich.table import Table
from rich.text import Text

from tui_gym.algorithms import ALGORITHMS
from tui_gym.cli.flags import (
    add_param_flag,
    add_wrapper_flag,
    key_values,
    output_file,
    wrapper_choices,
)
from tui_gym.cli.flags import int_in as _int_in
from tui_gym.cli.flags import seed_number as _seed
from tui_gym.cli.output import CliError, cli_errors, print_json, progress_bar, say_status, warn

if TYPE_CHECKING:
    from tui_gym.core.experiments import BestEffortHistory
    from tui_gym.session.experiments.compare import AlgorithmOutcome, CompareProgress

CLUSTER_ENV = "TUI_GYM_CLUSTER"
RMS_LABEL = "RMS error of V"  # a prediction learner's figure, against the exact values
# Every seed's return of every episode is kept while a run lasts: these bound that memory.
_seeds = _int_in(1, 1000, "a number of seeds from 1 to 1,000")
_episodes = _int_in(1, 200_000, "a number of episodes from 1 to 200,000")

R = TypeVar("R")


def _common_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seeds", type=_seeds, default=10, metavar="N",
                        help="independent learners per algorithm (default 10)")
    parser.add_argument("--episodes", type=_episodes, default=500, metavar="E",
                        help="episodes each learner trains for (default 500)")
    parser.add_argument("--first-seed", type=_seed, default=0, metavar="S",
                        help="seeds are S, S+1, ... (default 0)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        dest="settings", help="a hyperparameter for every algorithm that has it "
                        "(repeatable), e.g. --set epsilon_start=0.1")
    add_param_flag(parser)
    add_wrapper_flag(parser)
    parser.add_argument("--processes", type=_int_in(0, 1024, "a number of processes"),
                        default=None, metavar="P",
                        help="batches at once in child processes (default: one per core; "
                        "0: in this process)")
    add_task_flags(parser)
    parser.add_argument("--json", action="store_true")


def add_task_flags(parser: argparse.ArgumentParser) -> None:
    """`--resume`, `--cluster`, `--db` and `--no-record`: where tasks run and are kept."""
    parser.add_argument("--resume", type=_int_in(1, 2**62, "a run id"), metavar="RUN",
                        help="carry on run RUN (the first id the command printed): only its "
                        "missing tasks run; the settings must be the same")
    parser.add_argument("--cluster", metavar="ADDRESS", default=os.environ.get(CLUSTER_ENV),
                        help="run the tasks on a Dask scheduler (tcp://host:8786), or on "
                        f"local:N workers started here (default: ${CLUSTER_ENV}, else "
                        "processes of this machine)")
    from tui_gym.cli.runs_command import add_history_flags

    add_history_flags(parser, "these runs")


def add_experiment_parsers(sub: Any) -> None:
    """The `compare` and `sweep` sub-commands."""
    names = ", ".join(cls.name for cls in ALGORITHMS)
    compare = sub.add_parser(
        "compare", help="compare learners over many seeds: mean return with a 95%% band",
        description="Every (algorithm, seed) learns from scratch; the per-episode online "
        "return is averaged over seeds with a 95% confidence band, and for games with an "
        "exact model the greedy policy's exact value is followed at checkpoints.",
    )
    compare.add_argument("game", metavar="GAME", help="a game name or Gymnasium id")
    compare.add_argument("--algorithms", required=True, metavar="A,B",
                         help=f"comma-separated learners: {names}")
    _common_options(compare)
    compare.add_argument("--csv", type=output_file, metavar="PATH",
                         help="write each episode's mean and band per algorithm to a CSV file")
    compare.add_argument("--width", type=_int_in(20, 400, "a width from 20 to 400"),
                         default=None, metavar="W", help="chart width in characters")

    sweep = sub.add_parser(
        "sweep", help="one learner over a grid of hyperparameter values, many seeds each",
        description="Every grid point trains the algorithm over the seeds, as `compare` does; "
        "the table lists each point's figures, and two keys also show as a coloured grid.",
    )
    sweep.add_argument("game", metavar="GAME", help="a game name or Gymnasium id")
    sweep.add_argument("--algorithm", required=True, metavar="NAME", help=f"the learner: {names}")
    sweep.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2",
                       help="a hyperparameter and its values (repeatable)")
    sweep.add_argument("--sample", type=_int_in(1, 400, "a number of points from 1 to 400"),
                       default=0, metavar="N", help="a random search: N points drawn from "
                       "the --range values instead of a grid")
    sweep.add_argument("--range", action="append", default=[], metavar="KEY=LOW:HIGH[:log]",
                       dest="ranges", help="where --sample draws a hyperparameter (repeatable), "
                       "e.g. --range learning_rate=0.01:1:log")
    sweep.add_argument("--sample-seed", type=_seed, default=0, metavar="S",
                       help="the seed of the points --sample draws (default 0)")
    _common_options(sweep)


def _shared(args: argparse.Namespace) -> dict[str, Any]:
    """The fields of a comparison's or a sweep's spec that their common flags give."""
    return {"seeds": args.seeds, "episodes": args.episodes,
            "settings": key_values(args.settings, "--set"),
            "game_params": key_values(args.params, "--param"),
            "wrappers": wrapper_choices(args.wrapper), "first_seed": args.first_seed}


@contextmanager
def run_history(args: argparse.Namespace) -> Iterator[BestEffortHistory | None]:
    """The run history to record in (None with --no-record, or when it cannot be opened);
    its writes never raise (see `unrecorded`)."""
    if args.no_record:
        yield None
        return
    from tui_gym.core.experiments import BestEffortHistory, RunHistoryError, resolve_db_path

    path = resolve_db_path(args.db)
    try:
        history = BestEffortHistory(path)  # makes the folder, or says why it cannot
    except (RunHistoryError, OSError) as exc:
        text = str(exc) if isinstance(exc, RunHistoryError) else f"{path}: {exc}"
        warn(f"not recording these runs: {text}")
        yield None
        return
    with history:
        yield history


def unrecorded(history: BestEffortHistory | None) -> bool:
    """Say, after the results, that they were not recorded when a write failed; whether so."""
    if history is None or history.failure is None:
        return False
    warn(f"these results were not recorded in the run history: {history.failure}")
    return True


@contextmanager
def ctrl_c_stops(stop: threading.Event, err: Console) -> Iterator[None]:
    """The first Ctrl+C sets `stop` (the run ends cleanly); a second one interrupts at once."""
    from tui_gym.core.engine.processes import handling

    def handler(signum: int, frame: Any) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()
        err.print("stopping: keeping what finished (Ctrl+C again to quit at once)", style="yellow")

    with handling(("SIGINT",), handler):
        yield


def _run_recorded(args: argparse.Namespace, out: Console, label: str, run: Callable[..., R],
                  spec: Any) -> tuple[R, BestEffortHistory | None]:
    """`run(spec, ...)` kept in the run history, with a progress bar on a terminal (not with
    --json); the first Ctrl+C stops it cleanly; its refusals as one line."""
    from tui_gym.session.experiments.cluster import ClusterError
    from tui_gym.session.experiments.compare import CompareError

    stop = threading.Event()
    with run_history(args) as history, ctrl_c_stops(stop, Console(stderr=True)):

        def running(progress: Callable[[CompareProgress], None] | None) -> R:
            with cli_errors(CompareError, ClusterError):
                return run(spec, progress=progress, stop=stop, resume=args.resume,
                           cluster=args.cluster, history=history, processes=args.processes,
                           status=say_status)

        if args.json or not out.is_terminal:
            return running(None), history
        bar = progress_bar(out, f"[bold]{label}[/]", "bar",
                           "{task.fields[landed]}/{task.fields[tasks]} tasks", "percent",
                           "elapsed", "ETA", "left")
        task = bar.add_task(label, total=None, landed=0, tasks="?")

        # The bar and the time left follow the episodes (they move while a task runs);
        # the count is of the tasks finished.
        def update(p: CompareProgress) -> None:
            bar.update(task, completed=p.done, total=p.total, landed=p.tasks_done,
                       tasks=p.tasks_total or "?")

        with bar:
            return running(update), history


def _resume_hint(group: int | None) -> str:
    return "" if group is None else f"; the same command with --resume {group} carries on"


def _number_text(value: float | None, ci: float | None = None, sign: bool = True) -> str:
    """A figure to 3 significant digits or so (signed unless not `sign`), ± its interval."""
    if value is None:
        return "—"
    digits = 3 if abs(value) < 1 else 2 if abs(value) < 10 else 1
    text = f"{value:{'+' if sign else ''}.{digits}f}"
    return f"{text} ± {ci:.{digits}f}" if ci is not None else text


def _settings_text(hp: dict[str, Any]) -> str:
    parts = []
    if "learning_rate" in hp:
        parts.append(f"α={hp['learning_rate']:g}")
    if "epsilon_start" in hp and "epsilon_final" in hp:
        start, final = hp["epsilon_start"], hp["epsilon_final"]
        parts.append(f"ε={start:g}" if start == final else f"ε={start:g}→{final:g}")
    if "discount" in hp:
        parts.append(f"γ={hp['discount']:g}")
    return " ".join(parts)


def cmd_compare(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.session.experiments.compare import CompareSpec, run_compare

    names = [n.strip() for n in args.algorithms.split(",") if n.strip()]
    if not names:
        raise CliError("--algorithms: name at least one, e.g. --algorithms q-learning,sarsa")
    spec = CompareSpec(game=args.game, algorithms=names, **_shared(args))
    result, history = _run_recorded(args, out, "comparing", run_compare, spec)
    if args.csv:
        _write_csv(args.csv, result.outcomes)
    if args.json:
        print_json("compare", result.to_json())
        unrecorded(history)
        return 130 if result.interrupted else 0
    if not result.outcomes:
        out.print("stopped before any episode finished; nothing to show")
        unrecorded(history)
        return 130
    out.print(_compare_table(result))
    width = args.width or max(20, min(100, out.width - 12))
    out.print(_compare_chart(result, width))
    if result.interrupted:
        kept = min(o.episodes for o in result.outcomes)
        what = (f"the first {kept:,} episodes of every seed" if kept < spec.episodes else
                "the seeds that finished")
        out.print(f"[yellow]interrupted:[/] kept {what}" + _resume_hint(result.group))
    if args.csv:
        out.print(f"curves written to {args.csv}", style="dim")
    if not unrecorded(history) and result.group is not None:
        ids = [str(o.run_id) for o in result.outcomes]
        noun = "run" if len(ids) == 1 else "runs"
        out.print(f"recorded in the run history as {noun} {', '.join(ids)} "
                  "(tui-gym runs show ID)", style="dim")
    return 130 if result.interrupted else 0


def _compare_table(result: Any) -> Table:
    spec = result.spec
    title = (f"{result.game}: {spec.seeds} seeds × {spec.episodes:,} episodes"
             + (f", optimum {result.optimum:+.3f}" if result.optimum is not None else ""))
    table = Table(title=title, title_justify="left")
    table.add_column("algorithm", style="bold")
    table.add_column("settings")
    figures = _figure_columns(table, result.outcomes)
    from tui_gym.terminal_chart import PALETTE

    for k, o in enumerate(result.outcomes):
        table.add_row(Text(o.algorithm, style=PALETTE[k % len(PALETTE)]),
                      _settings_text(dict(o.hyperparameters)), *figures(o))
    return table


def _figure_columns(table: Table, outcomes: Sequence[AlgorithmOutcome | None]
                    ) -> Callable[[AlgorithmOutcome | None], list[str]]:
    """Add the columns of an outcome's figures (the exact value and gap, and the RMS error,
    where any outcome has them); the cells of one outcome in them."""
    table.add_column("return, last 10%", justify="right")
    has_exact = any(o is not None and o.exact_value is not None for o in outcomes)
    if has_exact:
        table.add_column("greedy exact value", justify="right")
        table.add_column("gap", justify="right")
    has_rms = any(o is not None and o.rms_error is not None for o in outcomes)
    if has_rms:
        table.add_column(RMS_LABEL, justify="right")
    table.add_column("seeds", justify="right")

    def cells(o: AlgorithmOutcome | None) -> list[str]:
        if o is None:
            return ["—"] * (2 + 2 * has_exact + has_rms)
        row = [_number_text(o.mean_return_last.mean, o.mean_return_last.ci95)]
        if has_exact:
            row += [_number_text(o.exact_value, o.exact_ci95), _number_text(o.exact_gap)]
        if has_rms:
            row.append(_number_text(o.rms_error, o.rms_ci95, sign=False))
        return [*row, f"{o.seeds_done}/{o.seeds}"]

    return cells


def _compare_chart(result: Any, width: int) -> Text:
    from tui_gym.terminal_chart import ChartSeries, band_chart

    series = [ChartSeries(o.algorithm, c.episodes, c.mean, c.lo, c.hi)
              for o in result.outcomes for c in (o.smoothed or o.curve,)]
    window = max(o.smoothing for o in result.outcomes)
    smoothed = f", each seed's averaged over its last {window} episodes" if window > 1 else ""
    chart = band_chart(series, width, 14, y_label=f"online return per episode, mean of "
                       f"{result.spec.seeds} seeds{smoothed}", skip_start=True)
    for name, label in (("exact_curve", "greedy policy's exact value"), ("rms_curve", RMS_LABEL)):
        curves = [ChartSeries(o.algorithm, c.episodes, c.mean, c.lo, c.hi)
                  for o in result.outcomes if (c := getattr(o, name)) is not None]
        if curves:
            chart.append("\n\n")
            chart.append_text(band_chart(curves, width, 8, y_label=label))
    return chart


def _write_csv(path: str, outcomes: Sequence[AlgorithmOutcome]) -> None:
    """Each episode's mean and band per algorithm (an episode a seed has not reached, or a
    band one seed has not, an empty cell)."""
    import numpy as np

    from tui_gym.core.experiments import Curve
    from tui_gym.core.experiments.runs import curves_csv
    from tui_gym.core.files import write_atomically

    if not outcomes:
        return
    curves = [Curve(f"{o.algorithm}.{part}", o.curve.episodes,
                    np.full(len(o.curve), np.nan) if values is None else values)
              for o in outcomes
              for part, values in (("mean", o.curve.mean), ("lo", o.curve.lo), ("hi", o.curve.hi))]
    try:
        write_atomically(path, curves_csv(curves)[0])
    except OSError as exc:
        raise CliError(f"--csv {path}: cannot write ({exc.strerror or exc})") from None


def cmd_sweep(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.session.experiments.sweep import Range, SweepSpec, run_sweep

    grid = {key: [v.strip() for v in values.split(",") if v.strip()]
            for key, values in key_values(args.grid, "--grid", "KEY=V1,V2,...").items()}
    ranges = {}
    for key, text in key_values(args.ranges, "--range").items():
        with cli_errors(ValueError, prefix=f"--range {key}: "):
            ranges[key] = Range.parse(text)
    spec = SweepSpec(game=args.game, algorithm=args.algorithm, grid=grid, **_shared(args),
                     ranges=ranges, samples=args.sample, sample_seed=args.sample_seed)
    result, history = _run_recorded(args, out, "sweeping", run_sweep, spec)
    if args.json:
        print_json("sweep", result.to_json())
    else:
        out.print(_sweep_table(result))
        if len(spec.grid) == 2 and not spec.ranges:
            out.print(_sweep_grid(result))
        if result.interrupted:
            out.print("[yellow]interrupted:[/] points show the episodes every seed finished"
                      + _resume_hint(result.group))
    unrecorded(history)
    return 130 if result.interrupted else 0


def _value_text(value: Any) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _sweep_table(result: Any) -> Table:
    spec = result.spec
    title = f"{result.game}, {spec.algorithm}: {spec.seeds} seeds × {spec.episodes:,} episodes"
    table = Table(title=title, title_justify="left")
    table.add_column("rank", justify="right")
    for key in spec.keys:
        table.add_column(key, justify="right", style="bold")
    figures = _figure_columns(table, [p.outcome for p in result.points])
    # A grid keeps its order (its rows follow the values); drawn points come best first.
    for point in result.ranked() if spec.ranges else result.points:
        table.add_row("—" if point.rank is None else str(point.rank),
                      *(_value_text(point.values[k]) for k in spec.keys), *figures(point.outcome),
                      style="green" if point.rank == 1 else None)
    return table


def _sweep_grid(result: Any) -> Table:
    """Two keys as rows and columns, each cell the final figure on a red-to-green scale."""
    (row_key, rows), (col_key, cols) = list(result.grid.items())
    figure = {(p.values[row_key], p.values[col_key]): p.figure for p in result.points}
    values = [v for v in figure.values() if v is not None]
    low, high = (min(values), max(values)) if values else (0.0, 1.0)
    exact = any(p.outcome is not None and p.outcome.exact_value is not None for p in result.points)
    rms = any(p.outcome is not None and p.outcome.rms_error is not None for p in result.points)
    what = RMS_LABEL if rms else "greedy exact value" if exact else "online return, last 10%"
    table = Table(title=f"{what}: {row_key} (rows) × {col_key} (columns)", title_justify="left")
    table.add_column(f"{row_key} \\ {col_key}", style="bold", justify="right")
    for c in cols:
        table.add_column(f"{c:g}" if isinstance(c, float) else str(c), justify="right")
    for r in rows:
        cells: list[Text | str] = [f"{r:g}" if isinstance(r, float) else str(r)]
        for c in cols:
            v = figure.get((r, c))
            if v is None:
                cells.append("—")
                continue
            share = 0.5 if high == low else (v - low) / (high - low)
            share = 1 - share if rms else share  # the lowest error is the best
            red, green = int(200 * (1 - share)) + 30, int(200 * share) + 30
            text = f" {v:.3f} " if rms else f" {v:+.3f} "
            cells.append(Text(text, style=f"bold black on rgb({red},{green},60)"))
        table.add_row(*cells)
    return table
