"""Waiting on a running app under the pilot: poll a condition with a deadline, never sleep
a fixed time; and driving an app while training or a comparison computes on a thread of
the test's process.

The pilot's `press()` and `pause()` wait until the process stops using the CPU, for up
to a second each time; while training or a comparison computes, that second always
runs out, and the work spends it. `send_key`, `wait_until`, `press_busy`, `wait_busy`
and `quit_busy` do without that wait. `open_train` presses t and waits until the Train
view is drawn; `figures_shown`, until its heatmaps and exact figures are.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from textual import events

from tui_gym.ui.train_view import TrainView

DEADLINE = 20.0  # seconds; generous for a loaded machine, never reached when things work
POLL = 0.02  # seconds the app runs on its own between two looks at the condition
SETTLE_ROUNDS = 50  # rounds of handling what is queued; a few suffice for one key


async def wait_until(pilot, predicate: Callable[[], bool], what: str,
                     timeout: float = DEADLINE) -> None:
    """Let the app run on its own timers until `predicate()` holds; fail with `what`
    after `timeout` seconds. Nothing more: the app's own timers have drawn what the
    checks read by then."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(POLL)


async def wait_for(pilot, predicate: Callable[[], bool], what: str,
                   timeout: float = DEADLINE) -> None:
    """`wait_until`, then one pause so the test reads a settled screen.

    Between two looks the app runs on its own timers (an asyncio sleep) rather than
    under a pilot pause: a pause also redraws the whole screen, so polling with pauses
    spends most of a core redrawing while the condition is still far off.
    """
    if predicate():
        return
    await wait_until(pilot, predicate, what, timeout)
    await pilot.pause()


_CHARS = {"space": " ", "full_stop": ".", "minus": "-", "plus": "+"}


def send_key(pilot, key: str) -> None:
    """Hand the app one key press, as the terminal driver does, and return at once.
    Follow it with `wait_until` on what the key does."""
    app = pilot.app
    event = events.Key(key, _CHARS.get(key, key if len(key) == 1 else None))
    event.set_sender(app)
    app.post_message(event)


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
    """Press `keys` one after the other (through the app's bindings, as a pressed key
    goes), the app settled after each."""
    for key in keys:
        pilot.app.simulate_key(key)
        await settle(pilot)


async def quit_busy(pilot) -> None:
    """Press q (through the app's bindings) and wait until the app has ended."""
    send_key(pilot, "q")
    await wait_until(pilot, lambda: pilot.app.return_code is not None, "the app to quit")


async def wait_busy(pilot, predicate: Callable[[], bool], what: str,
                    timeout: float = DEADLINE) -> None:
    """`wait_until`, then `settle`."""
    await wait_until(pilot, predicate, what, timeout)
    await settle(pilot)


async def open_train(pilot) -> TrainView:
    """Press t and wait until the Train view is drawn (from then on the app's timer shows
    each new snapshot in it)."""
    app = pilot.app

    def drawn() -> bool:  # it took the keyboard, then its first frame was drawn
        view, focused = app._train_ready(), app.focused
        return (view is not None and focused is not None
                and view in focused.ancestors_with_self and not app._train_appearing)

    await pilot.press("t")
    await wait_for(pilot, drawn, "the Train view drawn")
    view = app.query_one(TrainView)
    assert view.display
    return view


async def figures_shown(pilot, view: TrainView) -> None:
    """Wait until the heatmaps and the exact figures on screen are the shown snapshot's,
    and drawn."""
    await wait_until(pilot, lambda: view.figures_shown, "the exact figures")
    await pilot.pause()
