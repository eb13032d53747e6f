"""The Train view mounted alone: a small host app that holds a session and its runner,
as `TuiGymApp` does, for checks where the rest of the app is not the point."""

from __future__ import annotations

from textual.app import App, ComposeResult

from tui_gym.core.runners import make_runner
from tui_gym.core.session import Session
from tui_gym.ui.train_view import TrainView


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
