"""The run history on the command line: `runs`, and the flags that say where runs are kept."""

from __future__ import annotations

import argparse
from datetime import datetime
from typing import Any

from rich.cells import cell_len
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from tui_gym.cli.flags import file_name as _path
from tui_gym.cli.flags import int_in, output_file
from tui_gym.cli.output import CliError, cli_errors, key_value_table, print_json, warn
from tui_gym.core.text import visible

_run_id = int_in(1, 2**63 - 1, "a run id (a positive integer, see `tui-gym runs`)")
_limit = int_in(0, 2**31 - 1, "a number of runs (0 for all)")
DB_HELP = "the run history file (default: $TUI_GYM_DB, else the data folder's runs.db)"
RUN_ID_HELP = "a run's id (`tui-gym runs` lists them)"
KINDS = ("train", "compare", "sweep", "app", "benchmark")


def _db_option(parser: argparse.ArgumentParser, *, inherit: bool = False) -> None:
    # On a sub-command, SUPPRESS keeps a `--db` given before the sub-command's name
    # (`tui-gym --db PATH train ...` and `tui-gym runs --db PATH show 3` both work).
    default = argparse.SUPPRESS if inherit else None
    parser.add_argument("--db", type=_path, metavar="PATH", default=default, help=DB_HELP)


def add_runs_parser(sub: Any) -> None:
    """The `runs` sub-command and its own sub-commands."""
    runs = sub.add_parser(
        "runs", help="list the run history (every train run and every run in the app)",
        description="The run history: every `train` run, every comparison and every run "
        "trained in the app, with its settings, curves and final figures.",
    )
    runs.add_argument("--json", action="store_true")  # each --json's help: `_document_json`
    _db_option(runs, inherit=True)
    runs.add_argument("--game", metavar="G", help="only this game's runs (e.g. blackjack)")
    runs.add_argument("--kind", choices=KINDS, help="only runs of this kind")
    runs.add_argument("--limit", type=_limit, metavar="N",
                      help="the newest N runs (default: a screenful; every run with --json; "
                      "0: every run)")
    runs.add_argument("--recover", action="store_true",
                      help="copy what can be read of a damaged history into a new file beside "
                      "it (the history itself is left as it is)")
    verbs = runs.add_subparsers(dest="runs_command", metavar="VERB")
    for name, text in (
        ("show", "everything about one run"),
        ("export", "write a run's curves to a CSV file or for TensorBoard"),
        ("rm", "remove one run (its curves and figures with it)"),
        ("prune", "remove the stored tasks of finished runs (their curves and figures stay) "
         "and give the space back"),
    ):
        verb = verbs.add_parser(name, help=text)
        if name != "prune":
            verb.add_argument("run_id", type=_run_id, metavar="ID", help=RUN_ID_HELP)
        if name == "export":
            where = verb.add_mutually_exclusive_group(required=True)
            where.add_argument("--csv", type=output_file, metavar="PATH",
                               help="one row per episode, one column per curve")
            where.add_argument("--tensorboard", type=_path, metavar="DIR",
                               help="TensorBoard event files under DIR (needs "
                               "tui-gym[tensorboard])")
        verb.add_argument("--json", action="store_true", default=argparse.SUPPRESS)
        _db_option(verb, inherit=True)


def add_history_flags(parser: argparse.ArgumentParser, runs: str, *, inherit: bool = False
                      ) -> None:
    """`--db PATH` and `--no-record` (do not keep `runs` in the history) on a command."""
    _db_option(parser, inherit=inherit)
    parser.add_argument("--no-record", action="store_true",
                        help=f"do not keep {runs} in the run history")


def add_app_options(parser: argparse.ArgumentParser) -> None:
    """`--db PATH` and `--no-history` for the app (`--record` is for games, not runs)."""
    _db_option(parser)
    parser.add_argument("--no-history", action="store_true",
                        help="keep nothing in the run history: the app's training runs are not "
                             "recorded, and its comparisons go when it ends")


def _when(seconds: float | None, full: bool = False) -> str:
    if seconds is None:
        return ""
    return datetime.fromtimestamp(seconds).strftime("%Y-%m-%d %H:%M:%S" if full else "%m-%d %H:%M")


def _duration(seconds: float | None) -> str:
    if seconds is None:
        return ""
    if seconds < 120:
        return f"{seconds:.1f} s"
    return f"{seconds / 60:.1f} min"


def _figure_text(figure: Any, interval: bool = True) -> str:
    if figure is None or figure.value != figure.value:
        return ""
    if figure.unit == "episodes" and figure.value.is_integer():
        return f"{int(figure.value):,}"  # a count
    text = f"{figure.value:+.4f}"
    if interval and figure.ci95 is not None:
        text += f" ± {figure.ci95:.4f}"
    return text


# The columns, and those that go first to last when the terminal is narrow.
_COLUMNS = (("id", "right"), ("kind", "left"), ("game", "left"), ("algorithm", "left"),
            ("seeds", "left"), ("started", "left"), ("took", "right"), ("return", "right"),
            ("gap", "right"))
_DROPPED_FIRST = ("took", "seeds", "started")
_GAP = 2  # spaces between columns
CAPTION = ("return: the mean online return over the last 10% of episodes; "
           "gap: the greedy policy's exact gap to the optimum")


def _runs_table(title: str, rows: list[dict[str, str]], width: int) -> tuple[Text, str]:
    """The runs in the columns that fit `width` (the least needed go first), cells never cut:
    the heading, and the lines as plain text so that thousands of runs print at once."""
    widths = {name: max([len(name), *(cell_len(row[name]) for row in rows)])
              for name, _ in _COLUMNS}
    shown = [name for name, _ in _COLUMNS]
    for name in _DROPPED_FIRST:
        if sum(widths[n] for n in shown) + _GAP * (len(shown) - 1) <= width:
            break
        shown.remove(name)
    justify = dict(_COLUMNS)

    def line(cells: dict[str, str]) -> str:
        pads = {n: " " * (widths[n] - cell_len(cells[n])) for n in shown}  # wide characters
        parts = [pads[n] + cells[n] if justify[n] == "right" else cells[n] + pads[n] for n in shown]
        return (" " * _GAP).join(parts).rstrip()

    total = sum(widths[n] for n in shown) + _GAP * (len(shown) - 1)
    text = Text(title + "\n\n", style="italic")
    text.append(line({n: n for n in shown}) + "\n", style="bold")
    text.append("─" * total)
    return text, "".join(line(row) + "\n" for row in rows)


def cmd_runs(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.core.experiments import RunHistoryError, list_runs

    verb = getattr(args, "runs_command", None)
    if args.recover:
        if verb is not None:
            raise CliError(f"--recover works on the whole history, not with `runs {verb}`")
        verb = "recover"
    if verb is not None:
        with cli_errors(RunHistoryError):
            done = _act(verb, args)
        lost = verb == "recover" and done.target is None  # no run could be read
        if args.json:
            print_json(f"runs {verb}", done.to_json())
        elif lost:
            warn(f"no run could be read from {visible(done.source, 160)} ({done.check}); it was "
                 "left as it was")
        elif verb == "recover":
            out.print(_recovered(done))
        elif verb == "show":
            out.print(_show_table(done))
        else:
            out.print(Text(visible(_said(verb, done, args), None)))
        return 2 if lost else 0
    game = args.game.strip().lower() if args.game else None
    limit = args.limit
    if limit is None:
        # A screenful: all but the title, a blank line, the header, its rule, the line saying
        # there are more, a blank line, the caption's two and the shell's prompt.
        limit = 0 if args.json else max(5, out.size.height - 9)
    with cli_errors(RunHistoryError):
        listing = list_runs(args.db, game=game, kind=args.kind, limit=limit or None)
    for bad in listing.damaged[:5]:
        warn(f"run {bad.id} cannot be read: {bad.reason} (`tui-gym runs rm {bad.id}` "
              "removes it)")
    if len(listing.damaged) > 5:
        warn(f"and {len(listing.damaged) - 5} more runs cannot be read")
    if args.json:
        print_json("runs", listing.to_json())
        return 0
    if not listing.runs:
        which = f" of {visible(args.game, 40)}" if args.game else ""
        out.print(Text(f"No runs{which} in {visible(listing.db, 160)} yet: `tui-gym train "
                       "GAME` and the app record theirs."))
        return 0
    rows = []
    for run in listing.runs:
        kind = str(run.kind) if run.status == "finished" else f"{run.kind} ({run.status})"
        seeds = run.seeds
        rows.append({
            "id": str(run.id), "kind": kind, "game": visible(run.game, 40),
            "algorithm": visible(run.algorithm, 40),
            "seeds": f"{len(seeds)} seeds" if len(seeds) > 3 else ", ".join(map(str, seeds)),
            "started": _when(run.started_at), "took": _duration(run.seconds),
            "return": _figure_text(run.figure("mean_return_last"), interval=False),
            "gap": _figure_text(run.figure("exact_gap"), interval=False),
        })
    title = f"Runs in {visible(listing.db, 160)}"
    heading, lines = _runs_table(title, rows, out.width)
    out.print(heading, soft_wrap=True)
    out.file.write(lines)  # plain text: rich would take seconds over thousands of lines
    listed = len(listing.runs) + len(listing.damaged)
    if listing.total > listed:
        out.print(Text(f"(the newest {listed:,} of {listing.total:,} runs: --limit N lists "
                       "more, --limit 0 every one)"))
    out.print(Text("\n" + CAPTION, style="dim"))
    return 0


def _act(verb: str, args: argparse.Namespace) -> Any:
    """What `runs VERB` does to the history (RunHistoryError when it cannot)."""
    from tui_gym.core import experiments as history
    from tui_gym.core.experiments.recover import recover

    if verb == "export" and args.csv is None:
        from tui_gym.core.experiments.tensorboard import export_run_tensorboard

        return export_run_tensorboard(args.run_id, args.tensorboard, args.db)
    return {"recover": lambda: recover(history.resolve_db_path(args.db)),
            "show": lambda: history.show_run(args.run_id, args.db),
            "rm": lambda: history.remove_run(args.run_id, args.db),
            "prune": lambda: history.prune_tasks(args.db),
            "export": lambda: history.export_run_csv(args.run_id, args.csv, args.db)}[verb]()


def _recovered(done: Any) -> Text:
    source, target = visible(done.source, 160), visible(done.target, 160)
    verdict = "SQLite finds it sound" if done.check == "ok" else f"SQLite finds: {done.check}"
    lost = f" ({done.unreadable:,} could not be read)" if done.unreadable else ""
    dropped = (f"; {done.curves_dropped:,} of them without their curves, which could not be read"
               if done.curves_dropped else "")
    return Text(f"copied {done.copied:,} runs from {source} into {target}{lost}{dropped}.\n"
                f"{source} was left as it was ({verdict}). To use the copy: "
                f"`tui-gym runs --db {target}`, or move it in place of the original "
                "while no tui-gym runs.")


def _show_table(record: Any) -> Table:
    run = record.summary
    settings = ", ".join(f"{k}={v}" for k, v in record.hyperparameters.items())
    wrappers = ", ".join(
        w.name + (f"({', '.join(f'{k}={v}' for k, v in w.params.items())})" if w.params else "")
        for w in record.wrappers
    )
    params = ", ".join(f"{k}={v}" for k, v in record.game_params.items())
    versions = record.versions
    rows = [
        ("kind", str(run.kind)), ("game", run.game + (f" ({params})" if params else "")),
        ("wrappers", wrappers or "none"), ("algorithm", run.algorithm),
        ("hyperparameters", settings), ("seeds", ", ".join(str(s) for s in run.seeds) or "none"),
        ("status", str(run.status)), ("started", _when(run.started_at, full=True)),
        ("ended", _when(run.ended_at, full=True)), ("took", _duration(run.seconds)),
    ]
    if run.group is not None:
        rows.append(("launched with run", str(run.group)))
    rows += [(figure.name.replace("_", " "), _figure_text(figure)) for figure in run.figures]
    rows += [(f"curve {c.name}", f"{len(c)} points, episodes {int(c.episodes[0]):,}.."
              f"{int(c.episodes[-1]):,}") for c in record.curves if len(c)]
    rows += [("saved agent", record.agent_path or "none"),
             ("versions", f"tui-gym {versions.tui_gym}, gymnasium {versions.gymnasium}, "
              f"numpy {versions.numpy}, Python {versions.python}")]
    # Rich reads markup in these cells: what came from the history is escaped for it.
    return key_value_table(f"Run {run.id}", [(escape(visible(k, 40)), escape(visible(v, 400)))
                                             for k, v in rows])


def _said(verb: str, done: Any, args: argparse.Namespace) -> str:
    """What `runs export`, `rm` or `prune` did, in one line."""
    from tui_gym.core.experiments import DamagedRun

    if verb == "prune":
        return (f"removed {done.tasks:,} stored tasks of {done.runs:,} finished runs from "
                f"{done.db} (their curves and figures stay; unfinished runs keep theirs, to "
                "resume)")
    if verb == "rm":
        run = done.run
        what = (f"it could not be read: {run.reason}" if isinstance(run, DamagedRun)
                else f"{run.kind} {run.game} {run.algorithm}")
        return f"removed run {run.id} ({what}) from {done.db}"
    if args.csv is not None:
        return f"wrote {done.rows} rows of {', '.join(done.columns[1:])} to {done.path}"
    return (f"wrote {done.scalars} values of {', '.join(done.tags)} to {done.path} "
            f"(tensorboard --logdir {done.logdir})")
