"""`tui-gym mcp`: the games as tools of a Model Context Protocol server over stdio (the
sub-command here runs without the MCP SDK, to say how to install it; `server` needs it)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

INSTALL_HINT = "tui-gym mcp needs the MCP SDK: pip install 'tui-gym[mcp]'"
EXIT_USAGE = 2


def add_parser(sub: Any) -> None:
    """Add `mcp` to the sub-command parsers `sub`."""
    from tui_gym.cli.flags import finite_number, positive_int

    mcp = sub.add_parser(
        "mcp", help="serve the games to language models (MCP over stdio)",
        description="A Model Context Protocol server over stdin/stdout: tools to list the "
        "games, start one, observe, step, hint, and score against the exact optimum.",
    )
    mcp.add_argument("--no-hints", action="store_true",
                     help="refuse the hint tool and hide verdicts (for fair benchmarks)")
    mcp.add_argument("--max-games", type=positive_int, default=8, metavar="N",
                     help="games running at once (default 8)")
    mcp.add_argument("--idle-timeout", type=finite_number, default=600.0, metavar="S",
                     help="seconds after which an idle game is closed (default 600)")


def cmd_mcp(args: argparse.Namespace, out: Any) -> int:
    if not args.idle_timeout > 0:
        raise ValueError("--idle-timeout must be a positive number of seconds")
    try:
        from tui_gym.mcp_server.server import run
    except ImportError as exc:
        if (exc.name or "").partition(".")[0] != "mcp":
            raise
        sys.stderr.write(INSTALL_HINT + "\n")
        return EXIT_USAGE
    run(args.max_games, args.idle_timeout, hints=not args.no_hints)
    return 0
