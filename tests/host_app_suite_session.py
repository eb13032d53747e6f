"""A small host app for a view that reads the app's session and runner: the view mounted
alone, without the whole app around it."""

from __future__ import annotations

from textual.app import App, ComposeResult

from tui_gym.core.runners import make_runner
from tui_gym.core.session import Session
from tui_gym.ui.train_view import TrainView


class TrainViewAlone(App[None]):
    """The Train view alone, over one session and a (never started) thread runner."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session
        self.runner = make_runner(session, "thread")

    def compose(self) -> ComposeResult:
        yield TrainView(id="train")

    @property
    def train_view(self) -> TrainView:
        return self.query_one(TrainView)

    def on_unmount(self) -> None:
        self.runner.close()
