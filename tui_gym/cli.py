"""The `tui-gym` command: the app with no sub-command, and headless sub-commands.

Every sub-command is a thin call into `tui_gym.core`: `envs`, `wrappers`,
`train`, `eval` and `optimal` print rich tables (or one JSON object with
`--json`). Bad arguments, an unknown env or wrapper, or an unreadable file
exit with code 2 and one clear line on stderr, never a traceback.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from rich.console import Console
from rich.table import Table

from tui_gym import __version__

EXIT_USAGE = 2


class CliError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


class _Parser(argparse.ArgumentParser):
    """argparse, but errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(EXIT_USAGE)


def _int_at_least(minimum: int, noun: str):
    """An argparse type: an integer (underscores allowed) no smaller than `minimum`."""

    def parse(text: str) -> int:
        try:
            value = int(text.replace("_", ""))
        except ValueError:
            value = minimum - 1
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected {noun}, got {text!r}")
        return value

    return parse


_positive_int = _int_at_least(1, "a positive integer")
_seed = _int_at_least(0, "a non-negative integer")


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (also used to document the CLI)."""
    parser = _Parser(
        prog="tui-gym",
        description="A terminal playground for reinforcement learning. "
        "With no command, opens the app.",
        epilog="examples:\n"
        "  tui-gym --env gridworld          open the app on GridWorld (? lists every key)\n"
        "  tui-gym train blackjack --save bj.tgym\n"
        "  tui-gym eval bj.tgym --json\n"
        "  tui-gym optimal blackjack --sab\n"
        "  tui-gym play gridworld --jsonl   a program plays through JSON lines\n"
        "  tui-gym COMMAND --help           the options of one command",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"tui-gym {__version__}")
    parser.add_argument("--env", default="blackjack", help="game to open (default: blackjack)")
    parser.add_argument("--seed", type=_seed, default=0, help="seed for every random thing")
    parser.add_argument("--load", metavar="PATH", help="open a saved agent")
    parser.add_argument(
        "--runner", choices=("process", "thread"), default="process",
        help="train in a child process (default) or on a thread of the app's process",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    sub.add_parser("envs", help="list the games")
    sub.add_parser("wrappers", help="list the wrapper catalog and the --wrapper syntax")

    train = sub.add_parser("train", help="train a Q-learning agent headless")
    train.add_argument("env", metavar="ENV", help="blackjack, gridworld or a Gymnasium id")
    train.add_argument("--episodes", type=_positive_int, help="episode budget")
    train.add_argument("--learning-rate", type=_finite)
    train.add_argument("--discount", type=_finite)
    train.add_argument("--epsilon-start", type=_finite)
    train.add_argument("--epsilon-final", type=_finite)
    train.add_argument("--epsilon-decay-fraction", type=_finite)
    train.add_argument("--seed", type=_seed, default=0, dest="train_seed")
    train.add_argument("--size", type=_positive_int, help="GridWorld size (default 5)")
    train.add_argument("--sab", action="store_true", help="Blackjack: Sutton & Barto rules")
    train.add_argument("--natural", action="store_true", help="Blackjack: 1.5 for a natural")
    train.add_argument(
        "--wrapper", action="append", default=[], metavar="SPEC",
        help="add a wrapper, e.g. TimeLimit:max_episode_steps=50 (repeatable, in order)",
    )
    train.add_argument(
        "--engine", choices=("auto", "scalar", "vector"), default="auto",
        help="auto: the vector engine when the wrappers have a batched form (default)",
    )
    train.add_argument(
        "--target-gap", type=_finite, metavar="G",
        help="Blackjack: stop once the greedy policy's exact gap to the optimum is <= G "
        "(budget defaults to 1,000,000 episodes then)",
    )
    train.add_argument("--eval-episodes", type=_positive_int, default=10_000)
    train.add_argument("--save", metavar="PATH", help="save the trained agent here")
    train.add_argument("--json", action="store_true", help="print one JSON object, no bar")

    ev = sub.add_parser("eval", help="evaluate a saved agent (greedy play + exact reference)")
    ev.add_argument("path", metavar="PATH")
    ev.add_argument("--episodes", type=_positive_int, default=10_000)
    ev.add_argument("--seed", type=_seed, default=None, dest="eval_seed")
    ev.add_argument("--json", action="store_true")

    opt = sub.add_parser("optimal", help="the exact optimal strategy and its value")
    opt.add_argument("env", metavar="ENV")
    opt.add_argument("--sab", action="store_true", help="Sutton & Barto rules")
    opt.add_argument("--natural", action="store_true", help="1.5 for a natural blackjack")
    opt.add_argument("--size", type=_positive_int, help="GridWorld size (default 5)")
    opt.add_argument("--json", action="store_true")
    play = sub.add_parser("play", help="play a game from a program (JSON lines on stdin/stdout)")
    play.add_argument("env", metavar="ENV")
    play.add_argument("--jsonl", action="store_true", required=True,
                      help="read one JSON request a line, write one JSON response a line")
    play.add_argument("--seed", type=_seed, default=None, dest="play_seed")
    play.add_argument("--size", type=_positive_int, help="GridWorld size (default 5)")
    play.add_argument("--sab", action="store_true", help="Blackjack: Sutton & Barto rules")
    play.add_argument("--natural", action="store_true", help="Blackjack: 1.5 for a natural")
    play.add_argument("--wrapper", action="append", default=[], metavar="SPEC")

    screenshots = sub.add_parser("screenshots", help="write the app's SVG screenshots")
    screenshots.add_argument("directory", nargs="?", default="screenshots", metavar="DIR")

    bench = sub.add_parser("bench", help="measure speed, live training, memory and start-up")
    bench.add_argument("--quick", action="store_true", help="a shorter run (under a minute)")
    bench.add_argument("--json", action="store_true", help="print one JSON object")
    return parser


def _env_kwargs(args: argparse.Namespace, env_id: str) -> dict[str, Any]:
    kwargs: dict[str, Any] = {}
    if env_id == "Blackjack-v1":
        if getattr(args, "sab", False):
            kwargs["sab"] = True
        if getattr(args, "natural", False):
            kwargs["natural"] = True
    elif getattr(args, "sab", False) or getattr(args, "natural", False):
        raise CliError("--sab and --natural apply to Blackjack only")
    if getattr(args, "size", None) is not None:
        if env_id == "Blackjack-v1":
            raise CliError("--size applies to GridWorld only")
        kwargs["size"] = args.size
    return kwargs


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `tui-gym` command; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    out = Console()
    err = Console(stderr=True)
    try:
        if args.command is None:
            return _run_app(args)
        from tui_gym.commands import COMMANDS

        return COMMANDS[args.command](args, out)
    except KeyboardInterrupt:
        err.print("interrupted", style="yellow")
        return 130
    except (CliError, ValueError, OSError) as exc:
        sys.stderr.write(f"tui-gym: error: {_one_line(exc)}\n")
        return EXIT_USAGE


def _one_line(exc: BaseException) -> str:
    text = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.filename:
        text = f"{exc.filename}: {exc.strerror or text}"
    return " ".join(text.split())


def _run_app(args: argparse.Namespace) -> int:
    from tui_gym.core.profiles import resolve_env_id

    env_id = resolve_env_id(args.env)
    try:
        from tui_gym.ui.app import run_app
    except ImportError as exc:  # pragma: no cover - only without the UI installed
        raise CliError(f"the app is not available ({exc}); try `tui-gym --help`") from None
    return run_app(env_id=env_id, seed=args.seed, load=args.load, runner=args.runner)


def print_json(data: dict[str, Any]) -> None:
    """One JSON object on stdout (NaN written as null)."""
    sys.stdout.write(json.dumps(_clean(data)) + "\n")
    sys.stdout.flush()


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    return value


def key_value_table(title: str, rows: Sequence[tuple[str, str]]) -> Table:
    """A two-column table for summaries."""
    table = Table(title=title, show_header=False, title_justify="left")
    table.add_column(style="bold")
    table.add_column(justify="right")
    for key, value in rows:
        table.add_row(key, value)
    return table
