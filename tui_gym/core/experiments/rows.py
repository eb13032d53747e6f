"""Reading the run history's rows as runs, each checked as it is read: `summary`, `record`."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

from tui_gym.core.experiments.codec import CurveFormatError, decode_curve, unpack_curves
from tui_gym.core.experiments.connection import WriterCheck
from tui_gym.core.experiments.figures import Figure
from tui_gym.core.experiments.records import (
    Curve,
    RunKind,
    RunRecord,
    RunStatus,
    RunSummary,
    Versions,
    WrapperSetting,
)
from tui_gym.core.text import nested_deeper, visible

MAX_NAME = 200  # characters of a game, algorithm, kind, status, figure or version
MAX_JSON = 256 * 1024  # characters of a settings or figures JSON text
MAX_SEEDS_JSON = 8 * 1024 * 1024  # characters of a run's seeds (a book figure's: 50,000)
MAX_PATH = 4096  # characters of a saved agent's path
MAX_DEPTH = 16  # nesting of a settings JSON value
MAX_CURVES_BYTES = 1024 * 1024  # a run's curves blob
EARLIEST, LATEST = 0.0, 32_503_680_000.0  # 1970-01-01 .. 3000-01-01, in seconds


class BadRow(ValueError):
    """A field of a row that does not read as what tui-gym writes there."""


# A run's fields as a query reads them, in the order `record` takes them (after the id):
# a table's alias and column, and the field's bound in characters (None: a number).
FIELDS: dict[str, int | None] = {
    "r.kind": MAX_NAME, "s.game": MAX_NAME, "s.algorithm": MAX_NAME, "r.seeds": MAX_SEEDS_JSON,
    "r.status": MAX_NAME, "r.started_at": None, "r.ended_at": None, "r.group_id": None,
    "r.figures": MAX_JSON, "r.writer": MAX_NAME, "s.game_params": MAX_JSON,
    "s.wrappers": MAX_JSON, "s.hyperparameters": MAX_JSON, "p.tui_gym": MAX_NAME,
    "p.gymnasium": MAX_NAME, "p.numpy": MAX_NAME, "p.python": MAX_NAME, "r.agent_path": MAX_PATH,
}
SUMMARY_FIELDS = 10  # the first ten: what a listing shows


def column(field: str, alias: bool = True) -> str:
    """A field of FIELDS as a query reads it (`alias` False: bare): a text cut one character past
    its bound, so an oversized one shows; a number as it is, else cut as a short text."""
    expr, cap = field if alias else field.partition(".")[2], FIELDS[field]
    if cap is None:
        return f"CASE WHEN typeof({expr}) IN ('integer', 'real', 'null') THEN {expr} " \
               f"ELSE substr({expr}, 1, 41) END"
    return f"substr({expr}, 1, {cap + 1})"


SUMMARY_COLUMNS = ", ".join(["r.id", *map(column, list(FIELDS)[:SUMMARY_FIELDS])])
SUMMARY_FROM = "FROM runs r LEFT JOIN settings s ON s.id = r.settings_id"
RECORD_COLUMNS = ", ".join(["r.id", *map(column, FIELDS)])
RECORD_FROM = SUMMARY_FROM + " LEFT JOIN platforms p ON p.id = r.platform_id"
CURVES_COLUMNS = (
    f"typeof(data), length(data), CASE WHEN typeof(data) = 'blob' AND length(data) <= "
    f"{MAX_CURVES_BYTES} THEN data END"
)


def _shown(value: object) -> str:
    return visible(repr(value), 40)


def _name(value: object, what: str, optional: bool = False) -> str:
    if optional and value in (None, ""):
        return ""
    if not isinstance(value, str) or not value or len(value) > MAX_NAME:
        raise BadRow(f"its {what} is not a name ({_shown(value)})")
    return value


def _time(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BadRow(f"its {what} is not a time ({_shown(value)})")
    if not EARLIEST <= value <= LATEST:  # NaN fails too
        raise BadRow(f"its {what} is not a time between 1970 and 3000 ({_shown(value)})")
    return float(value)


def _finite(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BadRow(f"{what} is not a number ({_shown(value)})")
    try:
        number = float(value)
    except OverflowError:
        raise BadRow(f"{what} is too large a number ({_shown(value)})") from None
    if not math.isfinite(number):
        raise BadRow(f"{what} is not a finite number ({_shown(value)})")
    return number


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON data")


def _json(text: object, what: str, limit: int = MAX_JSON) -> Any:
    if not isinstance(text, str):
        raise BadRow(f"its {what} are not JSON text ({_shown(text)})")
    if len(text) > limit:
        raise BadRow(f"its {what} are longer than {limit:,} characters")
    try:
        value = json.loads(text, parse_constant=_refuse_constant)
    except RecursionError:
        raise BadRow(f"its {what} are nested too deeply") from None
    except ValueError as exc:  # JSONDecodeError, a number too long for Python
        raise BadRow(f"its {what} are not JSON ({visible(exc, 60)})") from None
    # More brackets than the bound is the only way to nest past it: count them first.
    if text.count("[") + text.count("{") > MAX_DEPTH and nested_deeper(value, MAX_DEPTH):
        raise BadRow(f"its {what} are nested too deeply")
    return value


def _typed(text: object, what: str, kind: type, noun: str) -> Any:
    value = _json(text, what)
    if not isinstance(value, kind):
        raise BadRow(f"its {what} are not {noun} ({_shown(value)})")
    return value


def figures(text: object) -> tuple[Figure, ...]:
    found = []
    for item in _typed(text, "figures", list, "a list"):
        if not isinstance(item, list) or len(item) != 4:
            raise BadRow(f"a figure is not [name, value, unit, interval] ({_shown(item)})")
        name, number, unit, ci95 = item
        name = _name(name, "figure's name")
        what = f"figure {visible(name, 40)}"
        found.append(Figure(
            name, float("nan") if number is None else _finite(number, what),
            _name(unit, f"{what}'s unit", optional=True),
            None if ci95 is None else _finite(ci95, f"{what}'s interval"),
        ))
    return tuple(found)


def _seeds(text: object) -> tuple[int, ...]:
    value = _json(text, "seeds", MAX_SEEDS_JSON)
    if not isinstance(value, list) or not all(
        isinstance(s, int) and not isinstance(s, bool) and -(2**63) <= s < 2**64 for s in value
    ):
        raise BadRow(f"its seeds are not a list of whole numbers ({_shown(value)})")
    return tuple(value)


def summary(row: Sequence[Any], writers: WriterCheck) -> RunSummary:
    """The run of a row selected with SUMMARY_COLUMNS; BadRow naming what does not read."""
    run_id, kind, game, algorithm, seeds, status, started, ended, group, figures_text, writer = (
        row[:11]
    )
    try:
        run_kind = RunKind(kind)
    except ValueError:
        raise BadRow(f"its kind is not one tui-gym writes ({_shown(kind)})") from None
    try:
        run_status = RunStatus(status)
    except ValueError:
        raise BadRow(f"its status is not one tui-gym writes ({_shown(status)})") from None
    if run_status is RunStatus.RUNNING and writers.gone(writer):
        run_status = RunStatus.INTERRUPTED  # its process ended without saying how
    if group is not None and (isinstance(group, bool) or not isinstance(group, int)):
        raise BadRow(f"its group is not a run id ({_shown(group)})")
    return RunSummary(
        id=run_id, kind=run_kind, game=_name(game, "game"), algorithm=_name(algorithm, "algorithm"),
        seeds=_seeds(seeds), status=run_status, started_at=_time(started, "start"),
        ended_at=None if ended is None else _time(ended, "end"), figures=figures(figures_text),
        group=group,
    )


def _wrappers(text: object) -> tuple[WrapperSetting, ...]:
    wrappers = []
    for item in _typed(text, "wrappers", list, "a list"):
        if not isinstance(item, dict) or not isinstance(item.get("params"), dict):
            raise BadRow(f"a wrapper is not {{name, params}} ({_shown(item)})")
        wrappers.append(WrapperSetting(_name(item.get("name"), "wrapper's name"), item["params"]))
    return tuple(wrappers)


def curves(kind: object, length: object, blob: object) -> tuple[Curve, ...]:
    """A run's curves from its blob (selected with CURVES_COLUMNS); BadRow if they do not read."""
    if kind != "blob":
        raise BadRow(f"its curves are not a blob (SQLite holds {_shown(kind)})")
    if not isinstance(blob, bytes):
        raise BadRow(f"its curves take {length} bytes, over the {MAX_CURVES_BYTES:,} allowed")
    try:
        stored = unpack_curves(blob)
        return tuple(Curve(name, *decode_curve(data)) for name, data in stored.items())
    except (CurveFormatError, ValueError, OverflowError) as exc:
        raise BadRow(f"its curves do not decode ({visible(exc, 80)})") from None


def record(row: Sequence[Any], run_curves: tuple[Curve, ...], writers: WriterCheck) -> RunRecord:
    """Everything about the run of a row selected with RECORD_COLUMNS."""
    game_params, wrappers, hyperparameters = row[11:14]
    versions = [_name(v, "version", optional=True) for v in row[14:18]]
    agent_path = row[18]
    if agent_path is not None and (not isinstance(agent_path, str) or len(agent_path) > MAX_PATH):
        raise BadRow(f"its saved agent's path is not a path ({_shown(agent_path)})")
    return RunRecord(
        summary=summary(row, writers),
        game_params=_typed(game_params, "game parameters", dict, "an object"),
        wrappers=_wrappers(wrappers),
        hyperparameters=_typed(hyperparameters, "hyperparameters", dict, "an object"),
        versions=Versions(*versions), curves=run_curves, agent_path=agent_path,
    )
