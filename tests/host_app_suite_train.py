"""The Train view mounted alone (a small host app that holds a session and its runner, as
`TuiGymApp` does), and driving an app while training runs without waiting for an idle
process."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from textual import events
from textual.app import App, ComposeResult

from tui_gym.core.runners import make_runner
from tui_gym.core.session import Session
from tui_gym.ui.train_view import TrainView

from .waiting import DEADLINE, POLL


class TrainHost(App[None]):
    """Only a `TrainView` over `session`, trained (when asked) on a worker thread."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session
        self.runner = make_runner(session, "thread")

    def compose(self) -> ComposeResult:
        yield TrainView(id="train")

    def on_unmount(self) -> None:
        self.runner.close(wait=False)


_CHARS = {"space": " ", "full_stop": ".", "minus": "-", "plus": "+"}


def send_key(pilot, key: str) -> None:
    """Hand the app one key press, as the terminal driver does, and return at once.

    `pilot.press` then waits for the process to go idle, which it never does while
    training runs on a worker thread: up to a second per key, training and redrawing
    all the while. Follow this with `wait_until` on what the key does.
    """
    app = pilot.app
    event = events.Key(key, _CHARS.get(key, key if len(key) == 1 else None))
    event.set_sender(app)
    app.post_message(event)


async def wait_until(pilot, predicate: Callable[[], bool], what: str,
                     timeout: float = DEADLINE) -> None:
    """`wait_for` for while training runs: poll `predicate` with a deadline, and end
    without the settling pause, which waits for an idle process that training does
    not give (the app's own timers have drawn what the checks read by then)."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(POLL)
