"""`tui-gym maps`: the built-in maps, one map's text, or a random map that can be solved."""

from __future__ import annotations

import argparse
import re
import sys

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from tui_gym.cli.flags import number_in, seed_number
from tui_gym.cli.output import CliError, cli_errors, print_json
from tui_gym.games.maps import GridMap, format_map
from tui_gym.games.maps.builtin import BUILTIN_MAPS, builtin_map, fits
from tui_gym.games.maps.files import read_map_file
from tui_gym.games.maps.random_map import MAX_DENSITY, random_map

_SIZE = re.compile(r"([0-9]{1,2})x([0-9]{1,2})", re.ASCII)


def add_maps_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    maps = sub.add_parser("maps", help="list the built-in maps, print one, or draw a random one")
    maps.add_argument("name", nargs="?", metavar="NAME", help="print this built-in map's text")
    maps.add_argument("--random", metavar="ROWSxCOLS", help="print a random solvable map")
    density = number_in(0.0, MAX_DENSITY, f"a number in [0, {MAX_DENSITY}]")
    maps.add_argument("--density", type=density, default=0.2, metavar="X",
                      help=f"share of obstacle cells in a random map (0 to {MAX_DENSITY})")
    maps.add_argument("--map-seed", type=seed_number, default=0, metavar="N", dest="maps_seed",
                      help="seed of a random map (default 0)")
    maps.add_argument("--obstacle", default="H", choices=("H", "C", "W"),
                      help="what a random map's obstacles are: holes, cliff or walls")
    maps.add_argument("--walled", action="store_true",
                      help="a random map of floor and walls only, all connected (GridWorld)")
    maps.add_argument("--check", metavar="PATH", help="read a map file and say what it holds")
    maps.add_argument("--json", action="store_true")


def _summary(grid_map: GridMap) -> dict[str, object]:
    return {
        "size": grid_map.size_text, "games": list(fits(grid_map)),
        "goal_reachable": grid_map.goal_reachable(), "text": format_map(grid_map),
    }


def cmd_maps(args: argparse.Namespace, out: Console) -> int:
    chosen = [bool(args.name), bool(args.random), bool(args.check)]
    if sum(chosen) > 1:
        raise CliError("give one of NAME, --random and --check")
    if not any(chosen):
        if args.json:
            print_json("maps", {"maps": [{"name": m.name, "description": m.description,
                                       **_summary(m.grid_map)} for m in BUILTIN_MAPS]})
            return 0
        table = Table(title="Built-in maps (tui-gym maps NAME prints one; --map-file PATH "
                      "plays it)", title_justify="left")
        for column in ("name", "size", "games", "what it is"):
            table.add_column(column)
        for entry in BUILTIN_MAPS:
            table.add_row(entry.name, entry.grid_map.size_text, ", ".join(fits(entry.grid_map)),
                          entry.description)
        out.print(table)
        return 0
    if args.name:
        try:
            entry = builtin_map(args.name)
        except KeyError as error:
            raise CliError(error.args[0]) from None
        head, grid_map = {"name": entry.name}, entry.grid_map
    elif args.random:
        match = _SIZE.fullmatch(args.random.strip().lower())
        if match is None:
            raise CliError(f"--random takes ROWSxCOLS, e.g. 8x8, not {args.random!r}")
        rows, cols = int(match[1]), int(match[2])
        with cli_errors(ValueError):
            grid_map = random_map(rows, cols, args.density, args.maps_seed, args.obstacle,
                                  walled=args.walled)
        head = {"name": f"random {rows}x{cols}"}
    else:
        grid_map = read_map_file(args.check)  # a MapError is one line naming where
        head = {"path": args.check}
    if args.json:
        print_json("maps", {**head, **_summary(grid_map)})
    elif args.check:
        games = ", ".join(fits(grid_map)) or "none"
        reach = "a goal can be reached" if grid_map.goal_reachable() else "no goal can be reached"
        out.print(f"{escape(args.check)}: a {grid_map.size_text} map; {reach}; played by: "
                  f"{games}", highlight=False, soft_wrap=True)
    else:
        sys.stdout.write(format_map(grid_map))  # as a file holds it: no colours, no wrapping
    return 0
