"""What each part of `ui/textual_internals.py` kept for speed buys: key latency while training
at max speed, and start-up, with that part left to Textual (`TUI_GYM_STOCK_TEXTUAL`)."""

from __future__ import annotations

import os
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass
from typing import Any
from unittest import mock

from tui_gym.bench import live, startup
from tui_gym.bench.figures import median

SPEED_PARTS = ("compositor", "resume", "focus")  # the others are behaviour, not speed


@dataclass(frozen=True)
class PartResult:
    """The app's figures with one part left to Textual."""

    part: str
    key_p50_ms: float
    key_p95_ms: float
    startup_s: float


def stock(part: str) -> AbstractContextManager[Any]:
    """While the block runs, apps made here or launched from here leave `part` to Textual."""
    from tui_gym.ui.textual_internals import STOCK_ENV

    return mock.patch.dict(os.environ, {STOCK_ENV: part})


def measure(seconds: float, presses: int, repeats: int, startup_repeats: int,
            progress: Callable[[str], None] | None = None) -> tuple[PartResult, ...]:
    """Each speed part off in turn, measured as the `live` and `startup` stages measure the
    app with every part on."""
    found = []
    for part in SPEED_PARTS:
        said = None if progress is None else (lambda text, part=part: progress(
            f"{text}, {part} left to Textual"))
        with stock(part):
            keys = live.measure(seconds, presses, repeats, (live.DEFAULT_RUNNER,),
                                said)[live.DEFAULT_RUNNER]
            if keys.errors:
                raise RuntimeError(f"{part} off: {'; '.join(keys.errors)}")
            launches = startup.measure(startup_repeats)
        found.append(PartResult(part, keys.key_latency_ms(50), keys.key_latency_ms(95),
                                median(launches.samples)))
    return tuple(found)
