"""Driving an app while a comparison computes on a thread of the test's process: keys
sent and conditions waited for without Textual's wait for an idle process.

The pilot's `press()` and `pause()` wait until the process stops using the CPU, for up
to a second each time; while a comparison computes, that second always runs out, and
the comparison spends it. Here a key goes the way a pressed key goes (a `Key` event to
the app, through its bindings) and the app is settled by letting it handle what it has
queued until nothing is left, so each step lasts only as long as the app needs.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from .waiting import DEADLINE, POLL

SETTLE_ROUNDS = 50  # rounds of handling what is queued; a few suffice for one key


async def settle(pilot) -> None:
    """Let the app handle every message queued, and those its handlers queue in turn,
    until no queue of the app or its screen holds one."""
    app = pilot.app
    for _ in range(SETTLE_ROUNDS):
        await pilot.pause(0)  # handles what is queued now; no wait for an idle process
        pumps = (app, *app.screen.walk_children(with_self=True))
        if not any(pump.message_queue_size for pump in pumps):
            return
    raise AssertionError(f"the app still had messages queued after {SETTLE_ROUNDS} rounds")


async def press_busy(pilot, *keys: str) -> None:
    """Press `keys` one after the other, the app settled after each."""
    for key in keys:
        pilot.app.simulate_key(key)
        await settle(pilot)


async def wait_busy(pilot, predicate: Callable[[], bool], what: str,
                    timeout: float = DEADLINE) -> None:
    """Let the app run until `predicate()` holds, then settle it; fail with `what` after
    `timeout` seconds."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(POLL)
    await settle(pilot)
