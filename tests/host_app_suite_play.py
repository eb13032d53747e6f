"""The Play view mounted alone: a tiny host app that gives the view what it reads from
`TuiGymApp` (the session, the play seed, no recording, no runner) and puts the keyboard
on the board once it is drawn, as the app does at start."""

from __future__ import annotations

from textual.app import App, ComposeResult

from tui_gym.core.session import Session
from tui_gym.ui.play_view import PlayView

# The Play view's size in the app at 120x40 (beside the side panel, under the header,
# over the key bar): mounted alone at this size, it lays out and wraps as there.
VIEW_SIZE = (76, 38)


class PlayHost(App[None]):
    """A `PlayView` filling the screen, playing `session`'s game."""

    def __init__(self, session: Session, play_seed: int | None = None) -> None:
        super().__init__()
        self.session = session
        self.play_seed = session.seed if play_seed is None else play_seed
        self.recording = None  # the view records to it when set; the app's switch is off here
        self.runner = None  # no training runs: the agent's figures come from the session

    @property
    def play_view(self) -> PlayView:
        return self.query_one(PlayView)

    def compose(self) -> ComposeResult:
        yield PlayView(id="play")

    def on_mount(self) -> None:
        self.call_after_refresh(self.play_view.focus_board)
