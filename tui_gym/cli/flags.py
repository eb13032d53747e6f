"""The flags' types (numbers read as `Param`s read them, file names; each failing with one
clear line) and the flags generated from `Param` schemas: game arguments, hyperparameters."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import Any, cast

from tui_gym.algorithms import ALGORITHMS, ALL_PARAMS, Learner
from tui_gym.cli.output import CliError, cli_errors
from tui_gym.core.params import Param, ParamError, digits_note, read_number, shown_value
from tui_gym.games import GAMES, Game, game_for, resolve_env_id

MAX_SEED = 2**63 - 2**32  # room for the seeds derived from it (evaluation adds to it)
FRESH_SEEDS = 1_000_000  # a seed drawn afresh is below this: short enough to type again


def fresh_seed() -> int:
    """A seed drawn from the system's randomness, for a run the user gave none."""
    import secrets

    return secrets.randbelow(FRESH_SEEDS)


def number_in(minimum: float, maximum: float, noun: str,
              integer: bool = False) -> Callable[[str], float]:
    """An argparse type: a number (ASCII digits, `_` allowed) in [minimum, maximum], a whole
    one if `integer`."""

    def parse(text: str) -> float:
        value = read_number(text)
        if value is None or math.isnan(value) or (integer and math.isfinite(value) and value % 1):
            raise argparse.ArgumentTypeError(
                f"expected {noun}, got {shown_value(text)}{digits_note(text)}")
        if not (math.isfinite(value) and minimum <= value <= maximum):
            raise argparse.ArgumentTypeError(
                f"{shown_value(text)} is out of range: expected {noun}")
        return int(value) if integer else float(value)

    return parse


def int_in(minimum: int, maximum: int, noun: str) -> Callable[[str], int]:
    """An argparse type: an integer (ASCII digits, `_` allowed) in [minimum, maximum]."""
    return cast(Callable[[str], int], number_in(minimum, maximum, noun, integer=True))


positive_int = int_in(1, 10**9, "a positive integer up to 1,000,000,000")
seed_number = int_in(0, MAX_SEED, f"an integer in [0, {MAX_SEED}]")
finite_number = number_in(-math.inf, math.inf, "a finite number")


def add_seed_flag(parser: argparse.ArgumentParser, dest: str, help: str,
                  default: int | None = 0) -> None:
    """`--seed S`, kept as `args.<dest>`."""
    parser.add_argument("--seed", type=seed_number, default=default, dest=dest, metavar="S",
                        help=help)


def add_wrapper_flag(parser: argparse.ArgumentParser) -> None:
    """`--wrapper SPEC`, repeatable, the first innermost."""
    parser.add_argument("--wrapper", action="append", default=[], metavar="SPEC",
                        help="add a wrapper, e.g. TimeLimit:max_episode_steps=50 (repeatable, "
                        "in order)")


def add_param_flag(parser: argparse.ArgumentParser) -> None:
    """`--param KEY=VALUE`, repeatable, kept as `args.params` (read by `key_values`)."""
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                        dest="params", help="a game parameter (repeatable), e.g. --param size=6")


def key_values(items: list[str], flag: str, shape: str = "KEY=VALUE") -> dict[str, str]:
    """`KEY=VALUE` flags as a dict (`-` in a key read as `_`); CliError for a malformed or
    repeated one."""
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip().replace("-", "_")
        filled = value.replace(",", " ") if "," in shape else value  # a list: not commas only
        if not sep or not key or not filled.strip():
            raise CliError(f"{flag} {item!r}: expected {shape}")
        if key in out:
            raise CliError(f"{flag} {key} is given twice")
        out[key] = value.strip()
    return out


def file_name(text: str) -> str:
    """An argparse type: a file name, which cannot be empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name, got an empty one")
    return text


def output_file(text: str) -> str:
    """An argparse type: a file that can be written, checked as the arguments are read (so
    before any work is done)."""
    from tui_gym.core.files import OutputPathError, check_output_path

    try:
        check_output_path(text)
    except OutputPathError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


HP_FLAGS = tuple(field.name for field in ALL_PARAMS)  # `train --learning-rate X`, ...
_PREFIX = "game_"


def flag(name: str) -> str:
    """`--learning-rate` for `learning_rate`."""
    return "--" + name.replace("_", "-")


def _owners() -> dict[str, list[tuple[Game, Param]]]:
    owners: dict[str, list[tuple[Game, Param]]] = {}
    for game in GAMES:
        for param in game.params:
            owners.setdefault(param.name, []).append((game, param))
    return owners


def add_game_flags(parser: argparse.ArgumentParser) -> None:
    """One flag per game argument name; a true-or-false one may stand alone (`--sab`)."""
    group = parser.add_argument_group("game arguments (each game takes its own; see `envs`)")
    for name, owned in _owners().items():
        param = owned[0][1]
        games = ", ".join(game.title for game, _ in owned)
        if param.kind is bool:
            group.add_argument(flag(name), dest=_PREFIX + name, nargs="?", const="true",
                               metavar="BOOL", help=f"{games}: {param.help} (true or false)")
        else:
            metavar = {int: "N", float: "X", str: "NAME"}[param.kind]
            group.add_argument(flag(name), dest=_PREFIX + name, metavar=metavar,
                               help=f"{games}: {param.help} ({param.describe_range()})")
    mapped = ", ".join(game.title for game in GAMES if game.editable)
    group.add_argument("--map-file", dest=_PREFIX + "map_file", metavar="PATH",
                       help=f"{mapped}: play a map from a file (see `tui-gym maps`)")


def _parsed(args: argparse.Namespace, prefix: str, takers: dict[str, str],
            own: dict[str, Any], who: str) -> dict[str, Any]:
    """The flags given (`args.<prefix><name>` for each name in `takers`, who takes it in
    words), each read by `own[name]`; CliError of one line that names the flag."""
    values: dict[str, Any] = {}
    for name, owners in takers.items():
        text = getattr(args, prefix + name, None)
        if text is None:
            continue
        if name not in own:
            raise CliError(f"{flag(name)} applies to {owners}, not {who}")
        try:
            values[name] = own[name].parse(text)
        except ParamError as exc:  # the flag, not the field, so the user knows what to fix
            raise CliError(f"{flag(name)} {exc.reason}") from None
        except ValueError as exc:
            raise CliError(str(exc).replace(name, flag(name), 1)) from None
    return values


def game_kwargs(args: argparse.Namespace, game: Game) -> dict[str, Any]:
    """The arguments given for `game`, each read by the game's own `Param`."""
    takers = {name: " and ".join(g.title for g, _ in owned) for name, owned in _owners().items()}
    kwargs = _parsed(args, _PREFIX, takers, {p.name: p for p in game.params}, game.title)
    path = getattr(args, _PREFIX + "map_file", None)
    return kwargs if path is None else map_kwargs(path, game, kwargs)


def map_kwargs(path: str, game: Game, kwargs: dict[str, Any]) -> dict[str, Any]:
    """`kwargs` playing the map in the file at `path`; `CliError` of one line otherwise."""
    from tui_gym.games.maps.files import read_map_file

    if not game.editable:
        mapped = ", ".join(g.title for g in GAMES if g.editable)
        raise CliError(f"--map-file applies to {mapped}, not {game.title}")
    with cli_errors(ValueError, prefix="--map-file "):  # a MapError names the file, line, ...
        grid_map = read_map_file(path)
    with cli_errors(ValueError, prefix=f"--map-file {path}: "):
        return game.with_map(kwargs, grid_map)


def add_hyperparameter_flags(parser: argparse.ArgumentParser) -> None:
    """One flag per hyperparameter of any algorithm, read as text and parsed by the
    field itself; a field some algorithms lack says which have it."""
    for field in ALL_PARAMS:
        kind = getattr(field, "kind", str)
        metavar = {int: "N", float: "X", bool: "BOOL"}.get(kind, "WORD")
        owners = [cls.name for cls in ALGORITHMS if field in cls.params]
        only = "" if len(owners) == len(ALGORITHMS) else f"; {', '.join(owners)}"
        parser.add_argument(
            flag(field.name), metavar=metavar,
            help=f"{field.help} ({field.describe_range()}{only})",
        )


def hyperparameters(args: argparse.Namespace, cls: type[Learner]) -> dict[str, Any]:
    """The hyperparameter flags given, checked against the algorithm's schema; errors
    name the flag."""
    takers = {name: ", ".join(c.name for c in ALGORITHMS if any(f.name == name for f in c.params))
              for name in HP_FLAGS}
    return _parsed(args, "", takers, {field.name: field for field in cls.params}, cls.name)


def wrapper_choices(specs: list[str]) -> tuple[Any, ...]:
    """The wrappers `--wrapper SPEC` flags name, innermost first."""
    from tui_gym.core.wrappers import parse_wrapper_spec

    return tuple(parse_wrapper_spec(spec) for spec in specs)


def app_env(args: argparse.Namespace) -> tuple[str | None, dict[str, Any] | None]:
    """The env id and arguments the app opens on (`--env`, `--map-file`); CliError of one
    line for an unknown game or a map that cannot be read."""
    env_id = resolve_env_id(args.env) if args.env else None
    if not args.app_map_file:
        return env_id, None
    game = game_for(env_id) if env_id else GAMES[0]
    return env_id or game.env_id, map_kwargs(args.app_map_file, game, {})
