"""The board every game is drawn on: the `Board` base and its messages."""

from __future__ import annotations

from collections.abc import Hashable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar

from rich.style import Style
from rich.text import Text
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.geometry import Offset
from textual.message import Message
from textual.widget import Widget
from textual.widgets import Button

from tui_gym.ui.widgets.strip_widget import Line, StripWidget, segments_of


def arrow_bindings(up: str, down: str, left: str, right: str, group: str) -> list[Binding]:
    """The arrows and WASD making a board's four moves (the game's action names), as a group."""
    keys = (("up", "w", "↑", up), ("down", "s", "↓", down), ("left", "a", "←", left),
            ("right", "d", "→", right))
    shown = Binding.Group(group)
    return [Binding(f"{arrow},{letter}", f"act('{move}')", move, key_display=f"{glyph}/{letter}",
                    group=shown) for arrow, letter, glyph, move in keys]


# A new episode at any time (n, r), or once this one is over (Enter), and what they do.
NEW_EPISODE_KEYS = [
    Binding("n,r", "new_episode", "New", key_display="n", tooltip="Start a new episode"),
    Binding("enter", "next_episode", "Next", show=False),
]
NEW_EPISODE_HELP = [
    ("n / r", "start a new episode (at any time)"),
    ("enter", "start a new episode once this one is over"),
]


class BoardCanvas(StripWidget):
    """The drawing area of a board: draws `board.picture(width, height)`, again only
    after `Board.redraw()` or a change of size or colours."""

    DEFAULT_CSS = """
    BoardCanvas { width: 1fr; height: 1fr; }
    """

    def __init__(self, board: Board) -> None:
        super().__init__(classes="board-canvas")
        self.board = board

    def picture_key(self) -> Hashable:
        return (self._version, self.content_size.height, self.board.rich_style)

    def draw(self, width: int) -> list[Line]:
        picture = self.board.picture(width, self.content_size.height)
        return segments_of(picture, self.app.console)

    def on_click(self, event: events.Click) -> None:
        offset = event.get_content_offset(self)
        board = self.board
        if offset is None or not board.interactive:
            return
        if board.agent_playing:
            board.post_message(board.TakeOver())
        else:
            board.canvas_clicked(offset)


class BoardButton(Button, can_focus=False):
    """A compact button under a board; the board keeps the focus when it is clicked."""


class Board(Widget):
    """Base of the game boards: draws a scene, posts moves when interactive."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    Board { width: 1fr; height: 1fr; layout: vertical; }
    Board.-interactive {
        border: round $foreground 25%;
        border-title-color: $text-muted;
        border-subtitle-color: $text-muted;
    }
    Board.-interactive:focus {
        border: round $accent;
        border-title-color: $accent;
        border-title-style: bold;
        border-subtitle-color: $text;
    }
    Board.-interactive.-agent, Board.-interactive.-agent:focus {
        border: round $warning;
        border-title-color: $text-warning;
        border-subtitle-color: $text-warning;
    }
    Board > .board-buttons { width: 1fr; height: 1; align-horizontal: center; }
    Board > .board-buttons > BoardButton { margin: 0 1; min-width: 10; }
    Board > .board-buttons > BoardButton.-suggested { text-style: bold; }
    """

    STYLE: ClassVar[str] = ""  # the prefix of the board's component classes
    # Buttons under the board: (label markup, action string run on the board).
    BUTTONS: ClassVar[tuple[tuple[str, str], ...]] = ()
    RESTART_ANYTIME: ClassVar[bool] = True  # may a new episode start before this one ends?
    over_hint = "The episode is over: start a new one."  # what to do once it is over
    unfinished_hint = "Finish this episode first."  # why not yet (when not RESTART_ANYTIME)
    # A drawing keeps the last one's cell shape while it fits (no jumps as the space around
    # changes); a replay draws each position afresh, to look the same however it is reached.
    KEEP_SHAPE: ClassVar[bool] = True

    @dataclass
    class Act(Message):
        """A person asked for a move, by the game's action name."""

        action: str

    class NewEpisode(Message):
        """A person asked for a new episode (deal, reset)."""

    class TakeOver(Message):
        """A person clicked or pressed a move while the agent plays: hand control back."""

    def __init__(self, *, interactive: bool = True, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.interactive = interactive
        self.scene: dict[str, Any] = {}
        self.reveal = True
        self.episode_over = False
        self.agent_playing = False  # the agent, not a person, makes the moves drawn
        self._drawing_held = False
        self.set_class(interactive, "-interactive", update=False)  # styled when mounted

    # --- structure ---------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield BoardCanvas(self)
        if self.interactive and self.BUTTONS:
            with Horizontal(classes="board-buttons"):
                for index, (label, _action) in enumerate(self.BUTTONS):
                    yield BoardButton(label, compact=True, name=str(index))

    def allow_focus(self) -> bool:
        return self.interactive

    @property
    def canvas(self) -> BoardCanvas:
        return self.query_one(BoardCanvas)

    # --- what the owner calls ------------------------------------------------
    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        """Draw a scene; `reveal` shows what is hidden during an episode (a hole card)."""
        self.scene = dict(scene)
        self.reveal = reveal
        self.redraw()

    def start_episode(self) -> None:
        """The next scene begins a new episode (a board may forget what it remembers)."""

    def set_episode_over(self, over: bool) -> None:
        """Tell the board whether the episode has ended (buttons follow)."""
        self.episode_over = over
        self.set_class(over, "-over")
        self._update_buttons()

    def set_agent_playing(self, playing: bool) -> None:
        """Say on the board whether the agent (not a person) is playing on it."""
        self.agent_playing = playing
        self.set_class(playing, "-agent")
        self._update_subtitle(focused=self.has_focus)
        self.redraw()

    @property
    def player_name(self) -> str:
        """Who the drawn player is: 'You', or 'Agent' on a passive board or while it plays."""
        return "Agent" if self.agent_playing or not self.interactive else "You"

    def takes_key(self, key: str) -> bool:
        """Whether one of the board's own bindings answers to `key` (e.g. "a")."""
        return any(binding.key == key for binding in Binding.make_bindings(self.BINDINGS))

    @contextmanager
    def drawn_once(self) -> Iterator[None]:
        """The scenes shown inside (a trail handed over at once) are drawn once, at the end."""
        self._drawing_held = True
        try:
            yield
        finally:
            self._drawing_held = False
            self.redraw()

    def redraw(self) -> None:
        if self.is_mounted and not self._drawing_held:
            for canvas in self.query(BoardCanvas):
                canvas.redraw()

    def key_help(self) -> list[tuple[str, str]]:
        """(key, what it does) for every key and click the board answers to."""
        return []

    @property
    def prompt(self) -> str:
        """What a person can do now, in a few words."""
        return ""

    # --- drawing (subclasses) ----------------------------------------------
    def _style(self, name: str) -> Style:
        return self.get_component_rich_style(f"{self.STYLE}--{name}")

    def picture(self, width: int, height: int) -> Text:
        """The board drawn to fit `width` x `height` cells."""
        return Text("")

    def canvas_clicked(self, offset: Offset) -> None:
        """A click on the drawing, at `offset` inside the canvas."""

    def button_enabled(self, action: str) -> bool:
        """Whether the button that runs `action` can be pressed now."""
        return True

    def button_suggested(self, action: str) -> bool:
        """Whether the button that runs `action` is the obvious next step."""
        return False

    # --- actions and buttons -----------------------------------------------
    def action_act(self, action: str) -> None:
        if self.agent_playing:
            self.post_message(self.TakeOver())
        elif self.interactive:
            self.post_message(self.Act(action))

    def action_new_episode(self) -> None:
        if self.agent_playing:
            self.post_message(self.TakeOver())
        elif self.interactive:
            self.post_message(self.NewEpisode())

    def action_next_episode(self) -> None:
        """Enter: a new episode, once this one is over (so a stray Enter loses nothing)."""
        if self.episode_over or self.agent_playing:
            self.action_new_episode()

    def on_mount(self) -> None:
        self._update_buttons()
        self._update_subtitle(focused=self.has_focus)

    def on_focus(self) -> None:
        self._update_subtitle(focused=True)

    def on_blur(self) -> None:
        self._update_subtitle(focused=False)

    def _update_subtitle(self, focused: bool) -> None:
        if not self.interactive:
            return
        if self.agent_playing:
            self.border_subtitle = "agent playing: any key takes over"
        else:
            self.border_subtitle = "" if focused else "click here to play"

    def _update_buttons(self) -> None:
        if not self.is_mounted:
            return
        for button in self.query(BoardButton):
            action = self.BUTTONS[int(button.name or 0)][1]
            button.disabled = not self.button_enabled(action)
            suggested = self.button_suggested(action)
            button.variant = "primary" if suggested else "default"
            button.set_class(suggested, "-suggested")

    async def on_button_pressed(self, event: Button.Pressed) -> None:
        if not isinstance(event.button, BoardButton):
            return
        event.stop()
        self.focus()
        await self.run_action(self.BUTTONS[int(event.button.name or 0)][1])


__all__ = [
    "NEW_EPISODE_HELP", "NEW_EPISODE_KEYS", "Board", "BoardButton", "BoardCanvas", "arrow_bindings",
]
