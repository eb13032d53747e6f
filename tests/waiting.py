"""Waiting on a running app under the pilot: poll a condition with a deadline, never sleep
a fixed time."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

DEADLINE = 20.0  # seconds; generous for a loaded machine, never reached when things work
POLL = 0.02  # seconds the app runs on its own between two looks at the condition


async def wait_for(pilot, predicate: Callable[[], bool], what: str,
                   timeout: float = DEADLINE) -> None:
    """Let the app run until `predicate()` holds; fail with `what` after `timeout` seconds.

    Between two looks the app runs on its own timers (an asyncio sleep) rather than
    under a pilot pause: a pause also redraws the whole screen, so polling with pauses
    spends most of a core redrawing while the condition is still far off. Once the
    condition holds, one pause lets the app handle what it has queued by then, so the
    test reads a settled screen.
    """
    if predicate():
        return
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(POLL)
    await pilot.pause()
