"""The pilot's wait for the screen, asked only of the widgets with something to do.

Textual's pilot, after each key, click and pause, waits until the app and every widget
of the screen has handled what was queued when it asked: it queues one callback on each
of them and waits for them all. A widget waiting in an empty queue has nothing queued,
and its callback only wakes it to run its idle handlers; on the app's screen that was
most of what a key press cost a test. Here the callback goes to the others only (a
widget handling a message, with messages queued, or with callbacks to run), and the wait
ends on the same condition. Where Textual's queues have another shape, the pilot's own
wait stays.

After each key and pause the pilot also waits for the process to go idle: Textual samples
its CPU time over 20 ms windows until one is nearly unused. Here the windows are 5 ms: a
test waits for what it reads by name (`tests/waiting.py`, or a pause, which draws the
screen), never on a window being long enough for a timer to fire in it.
"""

from __future__ import annotations

import asyncio
from typing import Any

import textual._wait
from textual._queue import Queue
from textual.pilot import Pilot, WaitForScreenTimeout


def _parked(node: Any) -> bool:
    """Waiting in an empty queue for its next message: nothing queued, nothing running."""
    queue = node._message_queue
    return not queue.values and bool(queue.ready_event._waiters) and not node._next_callbacks


async def _wait_for_busy_widgets(self: Pilot, timeout: float = 30.0) -> bool:
    """`Pilot._wait_for_screen` over the widgets that are not parked."""
    try:
        screen = self.app.screen
    except Exception:  # noqa: BLE001  (as the pilot's own: no screen, nothing to wait for)
        return False
    nodes = [self.app, *screen.walk_children(with_self=True)]
    count = 0
    handled = asyncio.Event()

    def one_handled() -> None:
        nonlocal count
        count -= 1
        if count == 0:
            handled.set()

    for node in nodes:
        if not _parked(node) and node.call_later(one_handled):
            count += 1
    if not count:
        return True
    waits = [asyncio.create_task(handled.wait()),
             asyncio.create_task(self.app._exception_event.wait())]
    _, pending = await asyncio.wait(waits, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
    for task in pending:
        task.cancel()
    if len(pending) == len(waits):
        raise WaitForScreenTimeout("Timed out while waiting for widgets to process pending "
                                   "messages.")
    return count == 0


IDLE_WINDOW = 0.005  # seconds of each look at the CPU time; Textual's own: 0.02


def wait_on_busy_widgets_only() -> bool:
    """Use the wait above when Textual's queues have the shape it reads; say whether."""
    queue: Any = Queue()
    shaped = (hasattr(queue, "values") and hasattr(queue, "ready_event")
              and hasattr(queue.ready_event, "_waiters")
              and hasattr(Pilot, "_wait_for_screen"))
    if shaped:
        Pilot._wait_for_screen = _wait_for_busy_widgets  # type: ignore[method-assign]
    if isinstance(getattr(textual._wait, "SLEEP_GRANULARITY", None), float):
        textual._wait.SLEEP_GRANULARITY = IDLE_WINDOW  # idle: under 5% of the window used
        textual._wait.SLEEP_IDLE = IDLE_WINDOW / 20
    return shaped
