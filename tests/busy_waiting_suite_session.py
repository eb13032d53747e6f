"""Driving an app while a worker thread of its own keeps the process busy (a comparison
running on the job's thread): a key sent and a condition waited for without Textual's
wait for an idle process.

The pilot's `press()` and `pause()` wait until the process stops using the CPU, for up
to a second each time; while a comparison computes on a thread of the test's process
that second always runs out, and the comparison spends it. Here the key goes the same
way a pressed key goes (a `Key` event to the app, through its bindings) and the screen
is settled by letting the app handle what it has queued, so each step lasts only as long
as the app needs.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from .waiting import DEADLINE, POLL


async def press_busy(pilot, key: str) -> None:
    """Press `key` and let the app handle it (its screen and widgets' queued messages)."""
    pilot.app.simulate_key(key)
    await pilot.pause(0)


async def wait_busy(pilot, predicate: Callable[[], bool], what: str,
                    timeout: float = DEADLINE) -> None:
    """Let the app run until `predicate()` holds, then handle what it has queued; fail
    with `what` after `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(POLL)
    await pilot.pause(0)
