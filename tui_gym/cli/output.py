"""What the `tui-gym` command prints: one-line errors, JSON objects and summary tables."""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from tui_gym.core.text import json_safe as _clean
from tui_gym.core.text import visible

# The version of each command's JSON object (its `"schema"`, first): up by one when a key is
# removed or renamed or changes its type or meaning; a new key leaves it as it is.
JSON_SCHEMAS: dict[str, int] = {
    "envs": 1, "wrappers": 1, "maps": 1, "algorithms": 1, "train": 1, "eval": 1, "optimal": 1,
    "runs": 1, "runs show": 1, "runs export": 1, "runs rm": 1, "runs prune": 1, "runs recover": 1,
    "plan": 1, "book": 1, "book list": 1, "compare": 1, "sweep": 1, "screenshots": 1, "bench": 3,
    "benchmark": 1,
}

_QUOTED = re.compile(r"'[^']{81,}'|\"[^\"]{81,}\"")  # an echoed value, as repr quotes it
_LONG_RUN = re.compile(r"\S{101,}")  # an echoed value with no quotes (argparse's lists)


class CliError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


@contextmanager
def cli_errors(*errors: type[Exception], prefix: str = "") -> Iterator[None]:
    """One of `errors` raised in the block as a `CliError`: `prefix`, then what it says."""
    try:
        yield
    except errors as exc:
        raise CliError(f"{prefix}{exc}") from None


class OutConsole(Console):
    """rich's Console, but a closed pipe ends the command the way every other write does."""

    def on_broken_pipe(self) -> None:
        self.quiet = True
        raise BrokenPipeError


def readable(message: str) -> str:
    """An error message as one line a person reads: control characters written as
    escapes, and input it echoes cut to its ends and its length."""
    text = _QUOTED.sub(lambda m: _cut(m.group()[1:-1], m.group()[0]), " ".join(message.split()))
    return visible(_LONG_RUN.sub(lambda m: _cut(m.group()), text), limit=None)


def _cut(text: str, quote: str = "") -> str:
    return f"{quote}{text[:20]}…{text[-8:]}{quote} ({len(text):,} characters)"


def print_json(command: str, data: dict[str, Any]) -> None:
    """`command`'s JSON object on stdout, its `schema` first (NaN written as null)."""
    data = {"schema": JSON_SCHEMAS[command], **data}
    sys.stdout.write(json.dumps(_clean(data)) + "\n")
    sys.stdout.flush()


def key_value_table(title: str, rows: Sequence[tuple[str, str]]) -> Table:
    """A two-column table for summaries."""
    table = Table(title=title, show_header=False, title_justify="left")
    table.add_column(style="bold")
    table.add_column(justify="right")
    for key, value in rows:
        table.add_row(key, value)
    return table


_BAR_COLUMNS = {"bar": BarColumn, "count": MofNCompleteColumn, "percent": TaskProgressColumn,
                "elapsed": TimeElapsedColumn, "left": TimeRemainingColumn}


def progress_bar(console: Console, *columns: str, transient: bool = True) -> Progress:
    """A progress bar of `columns`: rich's by name (bar, count, percent, elapsed, left),
    the others text templates."""
    return Progress(*(_BAR_COLUMNS[c]() if c in _BAR_COLUMNS else TextColumn(c) for c in columns),
                    console=console, transient=transient)


def warn(line: str) -> None:
    """A line for the user on standard error (not an error: the command goes on)."""
    sys.stderr.write(f"tui-gym: {line}\n")
    sys.stderr.flush()


def say_status(text: str) -> None:
    """A line of the engine's ("compiling the learners, once"), on standard error."""
    if text:
        Console(stderr=True).print(escape(text), style="dim")
