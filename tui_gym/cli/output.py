"""What the `tui-gym` command prints: one-line errors, JSON objects and summary tables."""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from typing import Any

from rich.console import Console
from rich.table import Table

__all__ = ["CliError", "OutConsole", "key_value_table", "print_json"]


class CliError(Exception):
    """A user-facing error: printed as one line, exit code 2."""


class OutConsole(Console):
    """rich's Console, but a closed pipe ends the command the way every other write does."""

    def on_broken_pipe(self) -> None:
        self.quiet = True
        raise BrokenPipeError


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
