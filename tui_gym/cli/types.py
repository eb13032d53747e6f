"""argparse types: numbers read as `Param`s read them (ASCII digits only; a value out of
range says so) and file names, each failing with one clear line. `output_file` checks a
file to write (`--save`, `--csv`, `--record`) as the arguments are read, so a path that
cannot be written is said before any work is done."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import cast

from tui_gym.core.params import digits_note, read_number, shown_value

__all__ = [
    "MAX_SEED", "file_name", "finite_number", "fresh_seed", "int_in", "number_in",
    "output_file", "positive_int", "seed_number",
]

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


def file_name(text: str) -> str:
    """An argparse type: a file name, which cannot be empty."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name, got an empty one")
    return text


def output_file(text: str) -> str:
    """An argparse type: a file that can be written (see `tui_gym.core.files`)."""
    from tui_gym.core.files import OutputPathError, check_output_path

    try:
        check_output_path(text)
    except OutputPathError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text
