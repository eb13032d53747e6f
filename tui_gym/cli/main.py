"""The `tui-gym` command's entry point and parser (the app with no sub-command): bad arguments
exit 2 with one line on stderr; a pipe closed early (`| head -1`) exits 141, as for `cat`."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import re
import sys
import textwrap
from collections.abc import Sequence
from typing import Any, NoReturn

from rich.console import Console

from tui_gym import __version__
from tui_gym.algorithms import ALGORITHMS, DEFAULT_ALGORITHM
from tui_gym.cli.flags import (
    add_game_flags,
    add_hyperparameter_flags,
    add_seed_flag,
    add_wrapper_flag,
    app_env,
    finite_number,
    fresh_seed,
    output_file,
    positive_int,
    seed_number,
)
from tui_gym.cli.maps_command import add_maps_parser
from tui_gym.cli.output import JSON_SCHEMAS, CliError, OutConsole, readable

ENV_HELP = "a game (`tui-gym envs` lists them), a Gymnasium id, or MODULE:ID"
EXIT_USAGE = 2
EXIT_BROKEN_PIPE = 128 + 13  # what a shell reports for a command ended by SIGPIPE


class _Parser(argparse.ArgumentParser):
    """argparse, but errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {readable(message)}\n")
        raise SystemExit(EXIT_USAGE)

    def _print_message(self, message: str, file: Any = None) -> None:
        # argparse drops write errors, so `--help | head -1` would end unlike every other
        # command; let a closed pipe reach `main`.
        if message:
            (file or sys.stderr).write(message)


# A negative number, `-inf` or `-nan` after a long option is that option's value; argparse
# would take `-inf` (or `-1e5`) for an option of its own and say "expected one argument".
_NEGATIVE_VALUE = re.compile(r"-(?:inf(?:inity)?|nan|[0-9.].*)", re.IGNORECASE)


def attach_negative_values(argv: Sequence[str]) -> list[str]:
    """`["--learning-rate", "-inf"]` as `["--learning-rate=-inf"]`, so argparse reads a value."""
    out: list[str] = []
    args = iter(argv)
    for arg in args:
        if arg == "--":
            return [*out, arg, *args]
        previous = out[-1] if out else ""
        if previous.startswith("--") and "=" not in previous and _NEGATIVE_VALUE.fullmatch(arg):
            out[-1] = f"{previous}={arg}"
        else:
            out.append(arg)
    return out


def _app_parser(add_help: bool = True) -> argparse.ArgumentParser:
    """The parser of the app's own options, those before any sub-command."""
    parser = _Parser(
        prog="tui-gym",
        description="A terminal playground for reinforcement learning. "
        "With no command, opens the app.",
        epilog="examples:\n"
        "  tui-gym envs                     the games, their flags and what they teach\n"
        "  tui-gym --env GAME               open the app on a game (? lists every key)\n"
        "  tui-gym train GAME --save agent.tgym\n"
        "  tui-gym train GAME --algorithm sarsa\n"
        "  tui-gym eval agent.tgym --json\n"
        "  tui-gym optimal GAME\n"
        "  tui-gym plan GAME --method policy-iteration   dynamic programming, headless\n"
        "  tui-gym book 4.3                 a figure of Sutton & Barto's, run and checked\n"
        "  tui-gym play GAME --jsonl        a program plays through JSON lines\n"
        "  tui-gym COMMAND --help           the options of one command",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        add_help=add_help,
    )
    parser.add_argument("--version", action="version", version=f"tui-gym {__version__}")
    parser.add_argument("--env", default="", help="game to open (default: the first of `envs`)")
    parser.add_argument("--seed", type=seed_number, default=None, metavar="S",
                        help="seed for every random thing (default 0; the app draws one afresh "
                        "each launch and shows it in its header)")
    parser.add_argument("--load", metavar="PATH", help="open a saved agent")
    parser.add_argument("--map-file", metavar="PATH", dest="app_map_file",
                        help="open a grid game (--env) on the map in this file")
    parser.add_argument("--record", type=output_file, metavar="PATH",
                        help="record your games in the app to this file (ctrl+r: on/off)")
    parser.add_argument(
        "--runner", choices=("process", "thread"), default="process",
        help="train in a child process (default) or on a thread of the app's process",
    )
    from tui_gym.cli.runs_command import add_app_options

    add_app_options(parser)
    return parser


def app_arguments(argv: Sequence[str]) -> argparse.Namespace | None:
    """The app's arguments when `argv` holds nothing but the app's options (no sub-command,
    no help), read as the full parser reads them without making every sub-command's
    parser; else None."""
    _, args, rest = _read_app_options(argv)
    if rest:
        return None
    args.command = None
    return args


def _read_app_options(
    argv: Sequence[str]
) -> tuple[argparse.ArgumentParser, argparse.Namespace, list[str]]:
    """The app's parser, the app options `argv` starts with, and the rest of `argv`."""
    parser = _app_parser(add_help=False)
    parser.add_argument("rest", nargs=argparse.REMAINDER)  # a sub-command and what follows
    args, unknown = parser.parse_known_args(argv)
    rest = [*args.rest, *unknown]
    del args.rest
    return parser, args, rest


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (also used to document the CLI)."""
    from tui_gym.benchmark.command import add_parser as add_benchmark_parser
    from tui_gym.cli.book_command import add_book_parser
    from tui_gym.cli.experiments_command import add_experiment_parsers
    from tui_gym.cli.plan_command import add_plan_parser
    from tui_gym.cli.replay_command import add_record_option, add_replay_parser
    from tui_gym.cli.runs_command import add_history_flags, add_runs_parser
    from tui_gym.mcp_server import add_parser as add_mcp_parser
    from tui_gym.web import add_serve_parser

    parser = _app_parser()
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    # Each `--json`'s help says its schema (`_document_json`).
    for name, text in (("envs", "list the games"),
                       ("wrappers", "list the wrapper catalog and the --wrapper syntax"),
                       ("algorithms", "list the learners and their parameters")):
        sub.add_parser(name, help=text).add_argument("--json", action="store_true")
    add_maps_parser(sub)
    names = ", ".join(cls.name for cls in ALGORITHMS)

    train = sub.add_parser("train", help="train an agent headless")
    train.add_argument("env", metavar="ENV", help=ENV_HELP)
    train.add_argument(
        "--algorithm", default=DEFAULT_ALGORITHM, metavar="NAME",
        help=f"the learner: {names} (default {DEFAULT_ALGORITHM}; `tui-gym algorithms`)",
    )
    # Read as text here and parsed by the fields themselves, so errors say "out of range".
    add_hyperparameter_flags(train)
    add_seed_flag(train, "train_seed", "seed of the training run (default 0; the evaluation "
                  "after it plays on S + 1)")
    add_game_flags(train)
    add_wrapper_flag(train)
    train.add_argument(
        "--engine", choices=("auto", "model", "env"), default="auto",
        help="auto: the compiled loop on the game's model when the wrappers let it follow "
        "(default); env: one transition at a time on the Gymnasium env",
    )
    train.add_argument(
        "--target-gap", type=finite_number, metavar="G",
        help="stop once the greedy policy's exact gap to the optimum is <= G "
        "(the budget defaults to five times the game's then)",
    )
    train.add_argument(
        "--eval-episodes", type=positive_int, default=10_000, metavar="N",
        help="greedy episodes to sample after the exact evaluation (default 10,000; "
        "a long-looping policy stops at the evaluation's step budget)",
    )
    train.add_argument("--follow", metavar="PATH",
                       help="a prediction learner follows this saved agent's greedy policy "
                       "(epsilon-greedy with --epsilon-final)")
    train.add_argument("--save", type=output_file, metavar="PATH",
                       help="save the trained agent here (the folder is checked first)")
    train.add_argument("--json", action="store_true")
    add_history_flags(train, "this run", inherit=True)

    ev = sub.add_parser("eval", help="evaluate a saved agent (greedy play + exact reference)")
    ev.add_argument("path", metavar="PATH", help="a saved agent (train --save, or ctrl+s in "
                    "the app)")
    ev.add_argument("--episodes", type=positive_int, default=10_000, metavar="N",
                    help="greedy episodes to sample (default 10,000; a long-looping policy "
                    "stops at the evaluation's step budget)")
    add_seed_flag(ev, "eval_seed", "seed of the sampled episodes (default: one derived from "
                  "the agent's training seed)", default=None)
    ev.add_argument("--json", action="store_true")

    opt = sub.add_parser("optimal", help="the exact optimal strategy and its value")
    opt.add_argument("env", metavar="ENV", help=ENV_HELP)
    add_game_flags(opt)
    opt.add_argument("--json", action="store_true")
    play = sub.add_parser("play", help="play a game from a program (JSON lines on stdin/stdout)")
    play.add_argument("env", metavar="ENV", help=ENV_HELP)
    play.add_argument("--jsonl", action="store_true", required=True,
                      help="read one JSON request a line, write one JSON response a line")
    add_seed_flag(play, "play_seed", "seed of the first episode (a reset may give its own)",
                  default=None)
    add_game_flags(play)
    add_wrapper_flag(play)
    add_record_option(play)
    add_replay_parser(sub)
    add_serve_parser(sub)
    add_runs_parser(sub)
    add_experiment_parsers(sub)
    add_plan_parser(sub)
    add_book_parser(sub)

    screenshots = sub.add_parser("screenshots", help="write the app's SVG screenshots")
    screenshots.add_argument("directory", nargs="?", default="screenshots", metavar="DIR",
                             help="the folder to write them to (default screenshots)")
    screenshots.add_argument("--json", action="store_true")

    bench = sub.add_parser("bench", help="measure speed, live training, memory and start-up")
    bench.add_argument("--quick", action="store_true",
                       help="a shorter run: fewer repeats and seeds, shorter time caps")
    bench.add_argument(
        "--algorithm", metavar="NAME", default=None,
        help=f"measure the per-algorithm figures for this learner only ({names}; default all)",
    )
    bench.add_argument("--json", action="store_true")

    add_mcp_parser(sub)
    add_benchmark_parser(sub)
    _document_json(parser)
    return parser


def json_flags(parser: argparse.ArgumentParser, path: str = "") -> dict[str, argparse.Action]:
    """Every sub-command that takes `--json` (`"runs show"`, ...) and its flag."""
    found: dict[str, argparse.Action] = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                command = f"{path} {name}".strip()
                flag = sub._option_string_actions.get("--json")
                if flag is not None:
                    found[command] = flag
                found.update(json_flags(sub, command))
    return found


def _document_json(parser: argparse.ArgumentParser) -> None:
    """Each `--json` flag says its schema version; the main help lists the commands."""
    flags = json_flags(parser)
    for command, action in flags.items():
        action.help = (f"print one JSON object instead (\"schema\": {JSON_SCHEMAS[command]}; "
                       "the README lists its keys under JSON outputs)")
    listed = textwrap.fill(
        ", ".join(flags) + ' take --json: one JSON object, whose "schema" is its version '
        "(the README lists each one's keys under JSON outputs)",
        width=78, initial_indent="  ", subsequent_indent="  ",
    )
    parser.epilog = f"{parser.epilog}\n\nJSON:\n{listed}"


def one_blas_thread() -> None:
    """Linear algebra on one thread here and in the processes this one starts, unless the
    user chose (`OPENBLAS_NUM_THREADS`): every solve is small, and idle BLAS threads spin on
    the cores that training and the UI need."""
    if "OPENBLAS_NUM_THREADS" not in os.environ:
        from threadpoolctl import threadpool_limits

        os.environ["OPENBLAS_NUM_THREADS"] = "1"
        threadpool_limits(1, user_api="blas")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `tui-gym` command; returns the exit code."""
    one_blas_thread()
    argv = attach_negative_values(sys.argv[1:] if argv is None else argv)
    err = Console(stderr=True)
    try:
        args = app_arguments(argv)
        if args is None:
            parser = build_parser()
            args = parser.parse_args(argv)
        # The app draws a seed afresh and shows it (so does each tab `serve` opens); commands
        # take 0.
        if args.seed is None and args.command != "serve":
            args.seed = fresh_seed() if args.command is None else 0
        out = OutConsole()
        if args.command is None:
            from tui_gym.ui.app import run_app

            env_id, env_kwargs = app_env(args)
            return run_app(env_id=env_id, seed=args.seed, load=args.load, runner=args.runner,
                           record=args.record, db=args.db, keep_history=not args.no_history,
                           env_kwargs=env_kwargs)
        _pass_app_options(parser, argv, args)
        if ":" in args.env:
            from tui_gym.games import resolve_env_id

            # The user's own `--env module:Id` imports its module on purpose, so a file that
            # names the same env (which alone never imports code) opens with it.
            resolve_env_id(args.env)
        module = importlib.import_module(_COMMAND_MODULES.get(args.command, "tui_gym.cli.commands"))
        code = getattr(module, f"cmd_{args.command}")(args, out)
        sys.stdout.flush()  # a closed pipe shows here, not at exit
        return code
    except BrokenPipeError:
        # Point stdout at /dev/null so the interpreter's own flush at exit finds no pipe
        # (with no real stdout, as when captured, there is nothing to flush).
        with contextlib.suppress(OSError, ValueError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)
        return EXIT_BROKEN_PIPE
    except KeyboardInterrupt:
        err.print("interrupted", style="yellow")
        return 130
    except (CliError, ValueError, OSError) as exc:
        text = str(exc) or type(exc).__name__
        if isinstance(exc, OSError) and exc.filename:
            text = f"{exc.filename}: {exc.strerror or text}"
        sys.stderr.write(f"tui-gym: error: {readable(text)}\n")
        return EXIT_USAGE


# The module of each sub-command `NAME` (its `cmd_NAME(args, console) -> exit code`), imported
# when it runs; the others are in `tui_gym.cli.commands`.
_COMMAND_MODULES = {
    "maps": "tui_gym.cli.maps_command", "replay": "tui_gym.cli.replay_command",
    "serve": "tui_gym.web", "runs": "tui_gym.cli.runs_command", "plan": "tui_gym.cli.plan_command",
    "compare": "tui_gym.cli.experiments_command", "sweep": "tui_gym.cli.experiments_command",
    "book": "tui_gym.cli.book_command", "mcp": "tui_gym.mcp_server",
    "benchmark": "tui_gym.benchmark.command",
}

# The app options a command opens its apps with; any other command takes an app option
# as its own flag of the same name (`tui-gym --db F runs` is `runs --db F`).
_OPENS_APPS = {"serve": ("--env", "--seed", "--load", "--map-file", "--runner", "--db",
                         "--no-history", "--record"), "replay": ("--runner",)}
_SAME_FLAG = {"--no-history": "--no-record"}


def _pass_app_options(
    parser: argparse.ArgumentParser, argv: Sequence[str], args: argparse.Namespace
) -> None:
    """Hand the app options given before the sub-command to it, or say where they go."""
    app, before, _ = _read_app_options(argv)
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    command = commands.choices[args.command]
    for action in app._actions:
        value = getattr(before, action.dest, action.default)
        if not action.option_strings or value == action.default:
            continue
        name = action.option_strings[0]
        if name in _OPENS_APPS.get(args.command, ()) or (name == "--env" and ":" in value):
            continue  # the command reads it (`--env MODULE:ID` imports the module)
        own = command._option_string_actions.get(_SAME_FLAG.get(name, name))
        if own is None and name == "--env":
            raise CliError(f"--env before `{args.command}` opens the app or serve; "
                           f"`{args.command}` takes its game after its name (see --help)")
        if own is None:
            raise CliError(f"{name} before `{args.command}` is an option of the app (and of "
                           f"serve), not of {args.command}: see `tui-gym {args.command} --help`")
        if getattr(args, own.dest, own.default) == own.default:
            setattr(args, own.dest, value)

