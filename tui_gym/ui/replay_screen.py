"""`ReplayScreen`: step through a recording, move by move, with the coach's word on each move."""

from __future__ import annotations

import functools
from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.content import Content
from textual.events import Resize
from textual.markup import escape
from textual.screen import ModalScreen
from textual.widget import Widget
from textual.widgets import Button, Header, OptionList, Static
from textual.widgets.option_list import Option

from tui_gym.core.recording.reader import Episode, Move, Position, Recording
from tui_gym.core.text import visible
from tui_gym.games import game_for
from tui_gym.games.words import format_reward, plural
from tui_gym.session.play import PlayStep
from tui_gym.ui.help_screen import HelpScreen
from tui_gym.ui.jump_screen import JumpScreen
from tui_gym.ui.play_view import StatusLines
from tui_gym.ui.widgets.board_kinds import KINDS, board_class
from tui_gym.ui.widgets.boards import Board
from tui_gym.ui.widgets.key_bar import KeyBar
from tui_gym.ui.widgets.numbers import cut

TRAIL_POSITIONS = 200  # scenes handed to a board before the one shown (its trail)
NARROW_WIDTH = 100  # below this the list of moves gives its room to the board
OBSERVATION_CHARS = 64
SOURCES = {  # who played, by the recording's `source`
    "app": "played in the app",
    "play": "played by a program",
    "benchmark": "a benchmark run",
}


@functools.cache
def _replay_class(kind_class: type[Board]) -> type[Board]:
    return type(f"Replay{kind_class.__name__}", (kind_class,),
                {"player_name": property(lambda self: self.replay_player), "KEEP_SHAPE": False})


def replay_board(kind: str, player: str) -> Board | None:
    """A passive board of `kind` whose player (a passive board's "Agent") is called `player`;
    None: no such board here."""
    if kind not in KINDS:
        return None
    board = _replay_class(board_class(kind))(interactive=False)
    board.replay_player = player  # type: ignore[attr-defined]
    return board


BUTTONS = (  # under the board: (label, id after "replay-", action on the screen)
    ("⏮ episode", "previous-episode", "episode(-1)"), ("◀ back", "back", "step(-1)"),
    ("forward ▶", "forward", "step(1)"), ("episode ⏭", "next-episode", "episode(1)"),
)


class ReplayButton(Button, can_focus=False):
    """A compact button under the board; the keyboard stays where it was."""


class ReplayScreen(ModalScreen[None]):
    """A recording, one position at a time."""

    DEFAULT_CSS = """
    ReplayScreen { background: $background; layout: vertical; }
    ReplayScreen #replay-title { height: auto; max-height: 2; padding: 0 1; }
    ReplayScreen #replay-body { height: 1fr; }
    ReplayScreen #replay-main { width: 1fr; height: 1fr; padding: 0 1; }
    ReplayScreen #replay-board { height: 1fr; min-height: 7; }
    ReplayScreen #replay-board > Board { height: 1fr; }
    ReplayScreen #replay-words { height: 1fr; padding: 1 2; color: $text-muted; }
    ReplayScreen #replay-buttons { height: 1; align-horizontal: center; }
    ReplayScreen ReplayButton { margin: 0 1; min-width: 8; }
    ReplayScreen #replay-moves { width: 36; height: 1fr; }
    ReplayScreen.-narrow #replay-moves { display: none; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("right,l", "step(1)", "Forward", key_display="→"),
        Binding("left,h", "step(-1)", "Back", key_display="←"),
        Binding("home", "edge(0)", "First", show=False),
        Binding("end", "edge(1)", "Last", show=False),
        Binding("n,right_square_bracket", "episode(1)", "Next episode", key_display="n"),
        Binding("N,left_square_bracket", "episode(-1)", "Previous", key_display="N"),
        Binding("j", "ask_episode", "Jump to…"),
        Binding("question_mark,f1", "help", "Help", key_display="?"),
        Binding("escape", "dismiss", "Close replay", key_display="esc"),
        Binding("q", "app.quit", "Quit"),
    ]

    def __init__(self, recording: Recording) -> None:
        super().__init__()
        self.recording = recording
        self.episode_index = 0  # into recording.episodes
        self.position = 0  # into the episode's positions
        self.board: Board | None = None
        self._words: Static | None = None  # the state in words, where there is no board
        self._board_kind: tuple[str, str] | None = None  # (kind, player) of the board shown
        self._listed: int | None = None  # the episode the move list shows

    # --- layout ------------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield Header()
        yield Static(id="replay-title")
        with Horizontal(id="replay-body"):
            with Vertical(id="replay-main"):
                yield Vertical(id="replay-board")
                yield StatusLines("replay")
                with Horizontal(id="replay-buttons"):
                    for label, name, action in BUTTONS:
                        yield ReplayButton(label, id=f"replay-{name}", action=f"screen.{action}",
                                           compact=True)
            yield OptionList(id="replay-moves")
        yield KeyBar()

    def on_mount(self) -> None:
        self.title = "tui-gym"
        self.sub_title = f"Replay: {self.recording.path.name}"
        self.set_class(self.app.size.width < NARROW_WIDTH, "-narrow")
        self.show(0, 0)
        self.query_one("#replay-moves", OptionList).focus()
        message = self.recording.message
        if message:
            self.notify(message, title="Replay", severity="warning", timeout=12)

    def on_resize(self, event: Resize) -> None:
        self.set_class(event.size.width < NARROW_WIDTH, "-narrow")

    # --- where we stand --------------------------------------------------------------
    @property
    def episode(self) -> Episode:
        return self.recording.episodes[self.episode_index]

    @property
    def current(self) -> Position:
        return self.episode.positions[self.position]

    def show(self, episode_index: int, position: int) -> None:
        """Stand at `position` of episode `episode_index` (both clamped) and draw it all."""
        episodes = self.recording.episodes
        episode_index = max(0, min(episode_index, len(episodes) - 1))
        episode = episodes[episode_index]
        position = max(0, min(position, len(episode.positions) - 1))
        self.episode_index, self.position = episode_index, position
        self._use_board(episode.game.board, "You" if episode.game.source == "app" else "Player")
        self._draw_board()
        self._show_title()
        self._show_status()
        self._show_moves()

    # --- actions -------------------------------------------------------------------------
    def action_step(self, delta: int) -> None:
        last = len(self.episode.positions) - 1
        target = self.position + delta
        if 0 <= target <= last:
            self.show(self.episode_index, target)
        elif target > last and self.episode_index + 1 < len(self.recording.episodes):
            self.show(self.episode_index + 1, 0)  # on into the next episode
        elif target < 0 and self.episode_index > 0:
            previous = self.recording.episodes[self.episode_index - 1]
            self.show(self.episode_index - 1, len(previous.positions) - 1)

    def action_edge(self, end: int) -> None:
        self.show(self.episode_index, len(self.episode.positions) - 1 if end else 0)

    def action_episode(self, delta: int) -> None:
        self.show(self.episode_index + delta, 0)

    def action_ask_episode(self) -> None:
        noun = self.episode.game.episode_noun

        def jump(number: int | None) -> None:
            if number is not None:
                self.show(number - 1, 0)

        self.app.push_screen(
            JumpScreen(len(self.recording.episodes), self.episode_index + 1, noun), jump
        )

    def action_help(self) -> None:
        self.app.push_screen(HelpScreen([("Replay", self.key_help())]))

    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("→ / l", "one move forward (on into the next episode at the end)"),
            ("← / h", "one move back"),
            ("↑ / ↓", "along the list of moves (click one to stand there)"),
            ("home / end", "the episode's start / its last move"), ("n / ]", "the next episode"),
            ("N / [", "the previous episode"), ("j", "jump to an episode by its number"),
            ("esc", "close the replay, back to the app"), ("q", "quit"),
        ]

    @on(OptionList.OptionHighlighted, "#replay-moves")
    def _highlighted(self, event: OptionList.OptionHighlighted) -> None:
        event.stop()
        if event.option_index != self.position:
            self.show(self.episode_index, event.option_index)

    # --- drawing ---------------------------------------------------------------------------
    def _use_board(self, kind: str, player: str) -> None:
        """The episode's kind of board (the state in words where there is none)."""
        if (kind, player) == self._board_kind:
            return
        self._board_kind = (kind, player)
        box = self.query_one("#replay-board", Vertical)
        box.remove_children()
        self.board = replay_board(kind, player)
        self._words = None if self.board is not None else Static(id="replay-words")
        widget: Widget | None = self.board or self._words
        assert widget is not None
        box.mount(widget)

    def _draw_board(self) -> None:
        episode, position = self.episode, self.position
        here = episode.positions[position]
        board = self.board
        if board is None:
            if self._words is not None:
                words = here.frame.text or _observation_text(here.frame.observation)
                self._words.update(Text(words))
            return
        reveal = here.move is not None and here.move.done
        board.start_episode()
        with board.drawn_once():
            for place in episode.positions[max(0, position - TRAIL_POSITIONS) : position + 1]:
                if place.frame.scene is not None:
                    try:
                        board.show_scene(place.frame.scene,
                                         reveal=reveal if place is here else False)
                    except Exception:  # a scene this board cannot read: it keeps the last one
                        continue
        board.set_episode_over(reveal)

    def _show_title(self) -> None:
        recording, episode = self.recording, self.episode
        game = episode.game
        noun = game.episode_noun
        chain = " → ".join(game.wrappers)
        wrappers = f" [$text-muted]({escape(chain)})[/]" if chain else ""
        optimal, judged = episode.judged
        parts = [
            f"[b]{escape(game.title)}[/]{wrappers}",
            f"{escape(noun)} [b]{self.episode_index + 1}[/] of {len(recording.episodes):,}",
            plural(len(episode.moves), "move"),
            f"return {format_reward(episode.total_return)}"
            + ("" if episode.finished else " [$text-warning](unfinished)[/]"),
        ]
        if judged:
            parts.append(f"{optimal}/{judged} optimal")
        total = episode.running_regret(len(episode.positions) - 1)
        parts.append(f"regret {_regret(total)}")
        if game.source:
            said = SOURCES.get(game.source, f"recorded by {game.source}")
            parts.append(f"[$text-muted]{escape(said)}[/]")
        self.query_one("#replay-title", Static).update(Content.from_markup("  ·  ".join(parts)))

    def _show_status(self) -> None:
        episode, here = self.episode, self.current
        noun = episode.game.episode_noun
        move = here.move
        coach, tone = "", ""
        if move is None:
            seed = f" (seed {episode.seed})" if episode.seed is not None else ""
            headline = f"Start of {noun} {self.episode_index + 1}{seed}"
        else:
            count = episode.end.steps if episode.end is not None else len(episode.moves)
            headline = (
                f"Move {move.step} of {count}: {move.action_name} → "
                f"reward {format_reward(move.reward)}"
            )
            if move.done:
                headline += f".  {self._outcome(episode, self.position)}"
            coach, tone = self._coach_line(episode, move)
        detail = [f"state: {here.frame.text or _observation_text(here.frame.observation)}"]
        if move is not None:
            detail.append(f"return so far {format_reward(episode.running_return(self.position))}")
            if move.note:
                detail.append(move.note)
        if here.frame.scene is None and self.board is not None:
            detail.append("no picture recorded here")
        self.query_one(StatusLines).show(headline, "  ·  ".join(detail), coach, tone, tone)

    def _coach_line(self, episode: Episode, move: Move) -> tuple[str, str]:
        """The coach's verdict, the move's regret and the episode's so far, and a tone."""
        so_far = f"regret so far {_regret(episode.running_regret(self.position))}"
        if move.verdict is None:
            return f"no verdict: no optimum to judge this move by · {so_far}", ""
        regret = f"regret {_regret(move.regret)}" + (
            " (no exact values for this game)" if move.regret is None else "")
        if move.verdict == "optimal":
            return f"✓ {move.action_name} was optimal · {regret} · {so_far}", "-good"
        best = " or ".join(move.optimal) or "another move"
        verdict = f"✗ {move.action_name} was not optimal (the optimum: {best})"
        return f"{verdict} · {regret} · {so_far}", "-bad"

    def _outcome(self, episode: Episode, position: int) -> str:
        """How the episode ended, in the game's words where this tui-gym knows the game."""
        here = episode.positions[position]
        move = here.move
        assert move is not None
        total = episode.running_return(position)
        try:
            game = game_for(episode.game.env_id, from_data=True)  # never imports code
            last = PlayStep(here.frame.observation, move.reward, move.terminated, move.truncated,
                            dict(here.frame.info), total, move.step, move.action)
            first_info = dict(episode.positions[0].frame.info) if episode.started else {}
            said = game.narrator.outcome_text(last, first_info, here.frame.scene or {})
            return visible(said, 200)  # the words may quote what the file holds
        except Exception:  # a game unknown here, or a recording its words cannot read
            pass
        how = "Episode over" if move.terminated else "Truncated by the time limit"
        return f"{how} after {move.step} moves, return {format_reward(total)}"

    def _show_moves(self) -> None:
        moves = self.query_one("#replay-moves", OptionList)
        # Only a person moving along the list asks to stand elsewhere: what is set here
        # posts nothing (a message from here would arrive after the next step, and undo it).
        with moves.prevent(OptionList.OptionHighlighted):
            if self._listed != self.episode_index:
                moves.set_options(_move_option(place) for place in self.episode.positions)
                self._listed = self.episode_index
            if moves.highlighted != self.position:
                moves.highlighted = self.position


def _move_option(place: Position) -> Option:
    move = place.move
    if move is None:
        return Option(Text.assemble(("start", "bold"), "  ", cut(place.frame.text or "", 22)))
    mark, style = "·", "dim"
    if move.verdict == "optimal":
        mark, style = "✓", "green"
    elif move.verdict is not None:
        mark, style = "✗", "red"
    regret = "" if move.regret is None or move.verdict == "optimal" else f" {move.regret:.3f}"
    return Option(
        Text.assemble(f"{move.step:>3} ", (move.action_name, "bold"), " ", (mark, style),
                      (regret, style), f"  {format_reward(move.reward)}" if move.reward else "")
    )


def _regret(value: float | None) -> str:
    return "–" if value is None else f"{value:.3f}"


def _observation_text(observation: object) -> str:
    return visible(observation, OBSERVATION_CHARS)

