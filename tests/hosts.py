"""Small host apps for a view mounted alone: each gives the view what it reads from
`TuiGymApp` (the session, and the runner or play seed), without the whole app around it."""

from __future__ import annotations

from textual.app import App, ComposeResult

from tui_gym.session.runners import make_runner
from tui_gym.session.session import Session
from tui_gym.ui.plan_view import PlanView
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.train_view import TrainView

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


class TrainHost(App[None]):
    """Only a `TrainView` over `session`, trained (when asked) on a worker thread, or in a
    child process with `runner="process"`."""

    def __init__(self, session: Session, runner: str = "thread") -> None:
        super().__init__()
        self.session = session
        self.runner = make_runner(session, runner)

    @property
    def train_view(self) -> TrainView:
        return self.query_one(TrainView)

    def compose(self) -> ComposeResult:
        yield TrainView(id="train")

    def on_unmount(self) -> None:
        self.runner.close(wait=False)


class PlanHost(App[None]):
    """Only a `PlanView` over `session`; an edited map rebuilds the session, as the app does."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session
        self.runner = None  # no training here: the agent's table is the session's

    @property
    def plan_view(self) -> PlanView:
        return self.query_one(PlanView)

    def compose(self) -> ComposeResult:
        yield PlanView(id="plan")

    def rebuild_map(self, env_kwargs: dict) -> bool:
        self.session.rebuild(env_kwargs=env_kwargs)
        self.plan_view.reload()
        return True
