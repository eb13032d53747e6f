"""`tui-gym book`: Sutton & Barto's figures, listed, or run one at a time and checked."""

from __future__ import annotations

import argparse
import threading
import time

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from tui_gym.book_text import claims_table, figure_parts, panel_text
from tui_gym.cli.experiments_command import add_task_flags, ctrl_c_stops, run_history, unrecorded
from tui_gym.cli.flags import add_seed_flag, positive_int
from tui_gym.cli.output import CliError, cli_errors, print_json, progress_bar
from tui_gym.session.book import figure_named, figures
from tui_gym.session.book.figure import (
    BookFigure,
    FigureOptions,
    FigureStopped,
    FigureTasks,
    heading,
)


def add_book_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    book = sub.add_parser("book", help="Sutton & Barto's figures: list them, or run one and "
                          "check the book's claims")
    book.add_argument("figure", nargs="?", metavar="FIGURE",
                      help="the figure to run, as the book numbers it (e.g. 4.3)")
    book.add_argument("--runs", type=positive_int, metavar="N",
                      help="independent runs (default: the figure's)")
    book.add_argument("--episodes", type=positive_int, metavar="E",
                      help="episodes a run (default: the figure's)")
    add_seed_flag(book, "book_seed", "the first run's seed (default 0)")
    book.add_argument("--full", action="store_true",
                      help="the book's own run and episode counts (slower); each finished "
                      "task is kept in the run history, so --resume carries it on")
    add_task_flags(book)
    book.add_argument("--json", action="store_true")


def cmd_book(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.session.experiments.cluster import ClusterError
    from tui_gym.session.experiments.compare import CompareError

    if args.figure is None:
        return _list(args, out)
    figure = figure_named(args.figure)
    if not (args.full or args.resume is not None):  # a figure's own small runs go unrecorded
        args.no_record = True
    with run_history(args) as history:
        if args.resume is not None and history is None:
            raise CliError(f"--resume {args.resume}: the run history is needed to resume")
        tasks = FigureTasks(history, args.resume, args.cluster)
        stop = threading.Event()  # the first Ctrl+C: the runs end at their next step
        options = FigureOptions(args.runs, args.episodes, args.book_seed, args.full,
                                stop=stop, tasks=tasks)
        began = time.perf_counter()
        try:
            with ctrl_c_stops(stop, Console(stderr=True)), cli_errors(CompareError, ClusterError):
                code = _run(figure, options, args, out)
        except FigureStopped as stopped:  # Ctrl+C: the runs end at their next step
            if tasks.group is not None and not unrecorded(history):
                Console(stderr=True).print(
                    f"kept {tasks.landed} of {tasks.tasks} tasks as runs {tasks.group}…; the "
                    f"same command with --resume {tasks.group} carries on", style="yellow")
            raise KeyboardInterrupt from stopped
        if tasks.tasks and not args.json:
            kept = "" if tasks.group is None or unrecorded(history) else (
                f"; kept in the run history as runs {tasks.group}… (tui-gym runs show "
                f"{tasks.group})")
            out.print(f"{tasks.tasks:,} tasks in {time.perf_counter() - began:,.0f} s{kept}",
                      style="dim")
    return code


def _run(figure: BookFigure, options: FigureOptions, args: argparse.Namespace, out: Console) -> int:
    if args.json:
        result = figure.run(options, lambda done, total, what: None)
        print_json("book", result.as_json())
        return 0 if result.ok else 1
    err = Console(stderr=True)
    progress = progress_bar(err, f"[bold]{heading(figure.name)}[/]", "bar", "count",
                            "{task.description}", "elapsed")
    task = progress.add_task("", total=None)

    def update(done: int, total: int, what: str) -> None:
        progress.update(task, completed=done, total=total, description=escape(what))

    with progress:
        result = figure.run(options, update)
    for part in figure_parts(result, out.width):
        out.print(part)
    for panel in result.panels:
        out.print(panel_text(panel, out.width), soft_wrap=True)
    for part in claims_table(result):
        out.print(part)
    return 0 if result.ok else 1


def _list(args: argparse.Namespace, out: Console) -> int:
    listed = figures()
    if args.json:
        print_json("book list", {"figures": [
            {"figure": f.name, "title": f.title, "world": f.world, "about": f.about,
             "runs": f.runs, "episodes": f.episodes} for f in listed]})
        return 0
    table = Table(title="Sutton & Barto's figures (tui-gym book FIGURE runs one)",
                  title_justify="left")
    for column in ("figure", "world", "what it shows"):
        table.add_column(column, style="bold" if column == "figure" else None)
    for f in listed:
        table.add_row(f.name, f.world, f"{escape(f.title)}\n[dim]{escape(f.about)}[/]")
    out.print(table)
    return 0
