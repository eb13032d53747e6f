"""The Play view: a person plays the session's game move by move.

`PlayView` owns a `HumanGame` (its own env, built like the session's, so the
wrappers chosen in the side panel apply to human play too) and the board the
game's profile asks for (`BOARDS[profile.board]`). The board turns keys and
clicks into `Board.Act` / `Board.NewEpisode` messages; this view answers them,
states what happened in plain words (the profile words outcomes, so nothing
here knows which game it is) and keeps a running tally of finished episodes.
The app calls `reload()` after a rebuild, `focus_board()` and `key_help()`.
"""

from __future__ import annotations

from typing import Any, ClassVar

from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical
from textual.content import Content
from textual.markup import escape
from textual.widgets import Static

from tui_gym.core.play import HumanGame, PlayError, PlayStep
from tui_gym.core.profiles.base import Advice, format_reward, to_jsonable
from tui_gym.ui.widgets.boards import BOARDS, Board

OBSERVATION_CHARS = 64  # a raw observation longer than this is cut short


class PlayView(Vertical):
    """Play the game yourself: the board, what happened, and the running tally."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    PlayView { width: 1fr; height: 1fr; padding: 0 1; }
    PlayView #play-title { height: 1; width: 1fr; padding: 0 1; }
    PlayView > Board { height: 1fr; min-height: 7; }
    PlayView #play-status {
        height: auto;
        width: 1fr;
        padding: 0 1;
        border-left: outer $foreground 30%;
    }
    PlayView #play-headline { text-style: bold; }
    PlayView #play-detail { color: $text-muted; }
    PlayView #play-hint { color: $text-warning; text-style: italic; display: none; }
    PlayView #play-status.-hint #play-hint { display: block; }
    PlayView #play-status.-good { border-left: outer $success; }
    PlayView #play-status.-good #play-headline { color: $text-success; }
    PlayView #play-status.-bad { border-left: outer $error; }
    PlayView #play-status.-bad #play-headline { color: $text-error; }
    PlayView #play-status.-even { border-left: outer $warning; }
    PlayView #play-status.-even #play-headline { color: $text-warning; }
    PlayView #play-tally { height: auto; width: 1fr; padding: 0 1; margin-top: 1; }
    Screen.compact PlayView { padding: 0; }
    Screen.compact PlayView #play-tally { margin-top: 0; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("i", "toggle_advice", "Advice", tooltip="Show what the exact optimum would do"),
    ]

    def __init__(
        self,
        *,
        name: str | None = None,
        id: str | None = None,
        classes: str | None = None,  # noqa: A002
    ) -> None:
        super().__init__(name=name, id=id, classes=classes)
        self.game: HumanGame | None = None
        self.board: Board | None = None
        self.truncated = 0  # finished episodes cut short by a time limit
        self._headline = Content()
        self._tone = ""
        self._hint = ""
        self.show_advice = False  # say what the exact optimum would do, and judge each move
        self._verdict = ""

    # --- layout ------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield Static(id="play-title")
        self.board = BOARDS[self.app.session.profile.board]()
        yield self.board
        with Vertical(id="play-status"):
            yield Static(id="play-headline")
            yield Static(id="play-detail")
            yield Static(id="play-hint")
        yield Static(id="play-tally")

    def on_mount(self) -> None:
        self.reload()

    # --- what the app calls --------------------------------------------------
    def reload(self) -> None:
        """Start afresh on the session's current game and wrappers: new game, tally, board."""
        session = self.app.session
        if self.game is not None:
            self.game.close()
        self.game = HumanGame(session, seed=self.app.play_seed)
        self.truncated = 0
        kind = BOARDS[session.profile.board]
        if type(self.board) is not kind:
            old = self.board
            had_focus = old is not None and old.has_focus
            self.board = kind()
            self.mount(self.board, before=self.query_one("#play-status"))
            if old is not None:
                old.remove()
            if had_focus:
                self.call_after_refresh(self.focus_board)
        self._show_title()
        self._start_episode()

    def focus_board(self) -> None:
        if self.board is not None and self.board.is_mounted:
            self.board.focus()

    def key_help(self) -> list[tuple[str, str]]:
        """(key, what it does) for playing the current game."""
        keys = self.board.key_help() if self.board is not None else []
        return [*keys, ("i", "advice: show the exact optimum's move and judge yours")]

    # --- playing -------------------------------------------------------------
    def on_board_act(self, message: Board.Act) -> None:
        message.stop()
        self.act(message.action)

    def on_board_new_episode(self, message: Board.NewEpisode) -> None:
        message.stop()
        self.new_episode()

    def act(self, action: str) -> None:
        """Make a move by its action name; a move that cannot be made now only says why."""
        game, board = self.game, self.board
        if game is None or board is None:
            return
        if game.done:
            self._say_hint(board.over_hint)
            return
        before = self._advice() if self.show_advice else None
        try:
            step = game.step(action)
        except PlayError as exc:
            self._say_hint(f"That move cannot be made: {exc}.")
            return
        except Exception as exc:  # a wrapper or env refused: say so, keep the app alive
            self._say_hint(f"The env refused the move: {exc}")
            return
        self._hint = ""
        self._verdict = _verdict(before, step, game.profile.action_names)
        if step.done:
            if step.truncated and not step.terminated:
                self.truncated += 1
            profile = game.profile
            self._headline = Content(profile.outcome_text(step, game.first_info, game.scene()))
            self._tone = "-even" if not step.terminated else _tone(step.reward)
        else:
            self._headline = Content(f"{action.capitalize()}: reward {format_reward(step.reward)}")
            self._tone = ""
        self._show_board()
        self._show_status()
        self._show_tally()

    def new_episode(self) -> None:
        """Deal or reset; not in the middle of an episode when the board says so."""
        game, board = self.game, self.board
        if game is None or board is None:
            return
        if not game.done and not board.RESTART_ANYTIME:
            self._say_hint(board.unfinished_hint)
            return
        self._start_episode()

    def _start_episode(self) -> None:
        game, board = self.game, self.board
        if game is None or board is None:
            return
        self._hint = ""
        try:
            game.reset()
        except Exception as exc:  # keep the app alive and say why
            self._headline = Content(f"The env could not start an episode: {exc}")
            self._tone = "-bad"
        else:
            noun = game.profile.episode_noun
            self._headline = Content.from_markup(
                f"New {escape(noun)}.  [not bold $text-muted]{escape(board.prompt)}[/]"
            )
            self._tone = ""
        self._verdict = ""
        board.start_episode()
        self._show_board()
        self._show_status()
        self._show_tally()

    # --- drawing ---------------------------------------------------------------
    def _show_board(self) -> None:
        game, board = self.game, self.board
        if game is None or board is None:
            return
        board.show_scene(game.scene(), reveal=game.done)
        board.set_episode_over(game.done)

    def _show_title(self) -> None:
        session = self.app.session
        chain = " → ".join(_short(choice.name, choice.params) for choice in session.applied)
        title = f"[b]{escape(session.profile.title)}[/]  [$text-muted]wrappers:[/] " + (
            f"[i $text-accent]{escape(chain)}[/]" if chain else "[$text-muted]none[/]"
        )
        self.query_one("#play-title", Static).update(Content.from_markup(title))

    def _say_hint(self, hint: str) -> None:
        self._hint = hint
        self._show_status()

    def _show_status(self) -> None:
        game = self.game
        last = game.last if game is not None else None
        detail = ""
        if game is not None and last is not None:
            parts = [self._verdict] if self._verdict else []
            parts.append(f"observation: {self._observation_text(last)}")
            progress = game.profile.progress_text(last, game.first_info)
            if progress:
                parts.append(progress)
            if last.steps:
                parts.append(f"return {format_reward(last.episode_return)}")
            if self.show_advice and not game.done:
                advice = self._advice()
                parts.append(advice.note if advice is not None else "no advice here")
            detail = "  ·  ".join(parts)
        status = self.query_one("#play-status")
        self.query_one("#play-headline", Static).update(self._headline)
        self.query_one("#play-detail", Static).update(Content(detail))
        self.query_one("#play-hint", Static).update(Content(self._hint))
        status.set_classes(self._tone)
        status.set_class(bool(self._hint), "-hint")

    def _advice(self) -> Advice | None:
        """What the exact optimum would do now (None when the game cannot say)."""
        game = self.game
        if game is None or game.done:
            return None
        try:
            return game.profile.advice(game.env, self.app.session.env_kwargs)
        except Exception:  # advice is a help, never a reason to fail
            return None

    def action_toggle_advice(self) -> None:
        self.show_advice = not self.show_advice
        self._verdict = ""
        self._show_status()
        self.notify(
            "Advice on: the exact optimum's move is shown and your moves are judged."
            if self.show_advice
            else "Advice off.",
            timeout=3,
        )

    def _observation_text(self, last: PlayStep) -> str:
        """The observation in the profile's words, or raw when wrappers reshaped it."""
        assert self.game is not None
        try:
            return self.game.profile.describe(last.observation)
        except Exception:  # a wrapper changed its shape: show it as it is
            raw = str(to_jsonable(last.observation))
            return raw if len(raw) <= OBSERVATION_CHARS else raw[: OBSERVATION_CHARS - 1] + "…"

    def _show_tally(self) -> None:
        game = self.game
        if game is None:
            return
        tally = game.tally
        parts = [
            f"[$text-muted]{escape(game.profile.episode_noun.capitalize())}s[/] "
            f"[b]{tally.episodes}[/]"
        ]
        for label, count, colour in (
            ("wins", tally.wins, "$text-success"),
            ("draws", tally.draws, "$text-warning"),
            ("losses", tally.losses, "$text-error"),
        ):
            style = f"b {colour}" if count else "b"
            parts.append(f"[$text-muted]{label}[/] [{style}]{count}[/]")
        if self.truncated:
            parts.append(f"[$text-muted]truncated[/] [b]{self.truncated}[/]")
        mean = "[$text-muted]–[/]"
        if tally.episodes:
            mean = f"[b]{format_reward(round(tally.mean, 3))}[/]"
            low, high = tally.confidence_interval()
            if low == low:  # NaN below two episodes
                mean += f" ± {(high - low) / 2:.3f} [$text-muted](95% CI)[/]"
        parts.append(f"[$text-muted]mean return[/] {mean}")
        self.query_one("#play-tally", Static).update(Content.from_markup("   ".join(parts)))


def _verdict(before: Advice | None, step: PlayStep, names: tuple[str, ...]) -> str:
    """'✓ optimal' or '✗ the optimum: stick' for the move just made ('' without advice)."""
    if before is None or not before.optimal or step.action is None:
        return ""
    if step.action in before.optimal:
        return "✓ optimal move"
    return "✗ the optimum: " + " or ".join(names[a] for a in before.optimal)


def _tone(reward: float) -> str:
    if reward > 0:
        return "-good"
    if reward < 0:
        return "-bad"
    return "-even"


def _short(name: str, params: tuple[tuple[str, Any], ...]) -> str:
    """A wrapper in a few characters: `TimeLimit(3)`, `StickyAction(0.25)`."""
    if not params:
        return name
    return f"{name}({', '.join(str(value) for _, value in params)})"
