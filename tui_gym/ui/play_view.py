"""The Play view: a person plays the session's game move by move."""

from __future__ import annotations

import random
from typing import TYPE_CHECKING, Any, ClassVar

from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Vertical
from textual.content import Content
from textual.markup import escape
from textual.timer import Timer
from textual.widgets import Static

from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.games.base import Advice
from tui_gym.games.words import format_reward, interval_text, plural, signed
from tui_gym.session.play import HumanGame, PlayError, PlayStep, Scorecard
from tui_gym.ui.exact_figures import LatestOnly
from tui_gym.ui.map_editing import SessionView
from tui_gym.ui.widgets.board_kinds import board_class
from tui_gym.ui.widgets.boards import Board
from tui_gym.ui.widgets.numbers import cut
from tui_gym.ui.widgets.scoreboard import Scoreboard

if TYPE_CHECKING:
    from tui_gym.session.session import Session

OBSERVATION_CHARS = 64  # a raw observation longer than this is cut short
WATCH_INTERVAL = 0.4  # seconds between the watched agent's moves: slow enough to follow
WATCH_PAUSE_TICKS = 3  # moves' worth of time a finished episode stays on the board
WATCH_SEED_OFFSET = 1  # the watched agent's game: seeded apart from the person's deals
COMPUTING = "its exact figures are being computed"  # until the first of them come
WATCHING = "Agent playing — press any key to take over"
TONE_COLOURS = {"good": "$text-success", "even": "$text-warning", "bad": "$text-error"}
# The modes `c` and `i` switch: the attribute, and what switching it on says.
MODES = {
    "coach": ("coach_on", "Coach on: each move is judged against the exact optimum."),
    "advice": ("show_advice", "Advice on: what the exact optimum and the agent would do here."),
}


class StatusLines(Vertical):
    """What happened, beside a bar in the tone of it: a bold headline, the coach's word on
    the move, the details, and the hint where the view gives one (`#PREFIX-...`)."""

    DEFAULT_CSS = """
    StatusLines { height: auto; padding: 0 1; border-left: outer $foreground 30%; }
    StatusLines.-good { border-left: outer $success; }
    StatusLines.-bad { border-left: outer $error; }
    StatusLines > .headline { text-style: bold; }
    StatusLines > .coach.-good { color: $text-success; }
    StatusLines > .coach.-bad { color: $text-error; }
    StatusLines > .detail { color: $text-muted; }
    """

    def __init__(self, prefix: str, *parts: str) -> None:
        super().__init__(id=f"{prefix}-status")
        self.prefix = prefix
        self.parts = ("headline", "coach", "detail", *parts)
        self._shown: tuple[Any, ...] = ()  # what the lines say

    def compose(self) -> ComposeResult:
        for part in self.parts:
            yield Static(id=f"{self.prefix}-{part}", classes=part)

    def show(self, headline: Content | str, detail: str, coach: str = "",
             coach_tone: str = "", tone: str = "", hint: str = "") -> None:
        """Say what happened; the bar and the coach's line take their tones (`-good`...)."""
        shown = (headline, detail, coach, coach_tone, tone, hint)
        if shown == self._shown:  # an update lays the view out again: none needed
            return
        self._shown = shown
        lines = dict(zip(self.parts, self.query(Static), strict=True))
        lines["headline"].update(Content(headline) if isinstance(headline, str) else headline)
        lines["coach"].update(Content(coach))
        lines["coach"].set_classes(f"coach {coach_tone}")
        lines["detail"].update(Content(detail))
        if "hint" in lines:
            lines["hint"].update(Content(hint))
        # All at once: the view is restyled only when they change.
        self.set_classes(f"{tone} {'-hint' if hint else ''} {'-coach' if coach else ''}")


AgentAsked = tuple["Session", TrainingSnapshot | None]  # the session detached, its snapshot


def _agent_figures(asked: AgentAsked) -> tuple[dict[str, float], str]:
    """The agent's exact scoreboard figures and why there are none ('' when there are)."""
    session, snapshot = asked
    return session.agent_figures(snapshot), session.exact_reason()


# What a game switch puts away of the person's play on a game (see `PlayView.put_away`).
_KEPT_ATTRIBUTES = (
    "game", "scorecard", "outcomes", "agent_game", "agent_card", "_watch_rng",
    "_headline", "_tone", "_hint", "_verdict", "_coach", "_coach_tone",
)


def _chain(session: Any) -> tuple[Any, ...]:
    """What a human game was built from: the game, its arguments and its wrappers."""
    return (session.env_id, tuple(sorted(session.env_kwargs.items())), session.applied)


class PlayView(SessionView):
    """Play the game yourself: the board, what happened, and the running tally."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    PlayView { width: 1fr; height: 1fr; padding: 0 1; }
    PlayView #play-title {
        height: 1; width: 1fr; padding: 0 1; text-wrap: nowrap; text-overflow: ellipsis;
    }
    PlayView > Board { height: 1fr; min-height: 7; }
    /* Room kept for the status lines, so the board keeps its size as they come and go. */
    PlayView #play-status { min-height: 6; width: 1fr; }
    PlayView #play-coach { display: none; }
    PlayView #play-status.-coach #play-coach { display: block; }
    PlayView #play-hint { color: $text-warning; text-style: italic; display: none; }
    PlayView #play-status.-hint #play-hint { display: block; }
    PlayView #play-status.-good #play-headline { color: $text-success; }
    PlayView #play-status.-bad #play-headline { color: $text-error; }
    PlayView #play-status.-even, PlayView #play-status.-agent { border-left: outer $warning; }
    PlayView #play-status.-even #play-headline,
    PlayView #play-status.-agent #play-headline { color: $text-warning; }
    PlayView #play-tally { height: auto; width: 1fr; padding: 0 1; margin-top: 1; }
    Screen.compact PlayView { padding: 0; }
    Screen.compact PlayView #play-status { min-height: 0; max-height: 7; overflow: hidden; }
    Screen.compact PlayView #play-tally { margin-top: 0; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("c", "mode('coach')", "Coach", tooltip="Judge each move against the optimum"),
        Binding("i", "mode('advice')", "Advice",
                tooltip="What the exact optimum and the agent would do"),
        # "a" where the board leaves it free (the grid board walks left on it): "A" always.
        Binding("a,A", "watch_agent", "Watch agent", tooltip="Let the greedy agent play"),
    ]

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.game: HumanGame | None = None
        self.board: Board | None = None  # the one shown
        self._boards: dict[type[Board], Board] = {}  # one of each kind shown so far
        self.outcomes: dict[str, int] = {}  # finished episodes by the narrator's tally word
        # Each game's play put away by a game switch: what it was built from, and the
        # `_KEPT_ATTRIBUTES` as they were.
        self._kept: dict[str, tuple[tuple[Any, ...], dict[str, Any]]] = {}
        self._headline = Content()
        self._tone = ""
        self._hint = ""
        self.show_advice = False  # say what the exact optimum and the agent would do
        self._verdict = ""  # advice's short judgement of the last move (coach off)
        self.coach_on = False  # judge each move in words
        self._coach = ""  # the coach's line on the last move
        self._coach_tone = ""
        self.scorecard = Scorecard()  # the person's record (tally, agreement, figures)
        # The agent's exact scoreboard figures, as of the last refresh (not per frame),
        # computed off the event loop.
        self.agent_figures: dict[str, float] | None = None
        self._exact_reason = COMPUTING  # why there are no exact figures, read with them
        self._agent_exact: LatestOnly[AgentAsked, tuple[dict[str, float], str]] = LatestOnly(
            self, _agent_figures)
        # Watching the agent play on the board.
        self.watch_interval = WATCH_INTERVAL
        self.watch_pause_ticks = WATCH_PAUSE_TICKS
        self.watching = False
        self.agent_game: HumanGame | None = None  # the watched agent's own game
        self.agent_card = Scorecard()  # the watched agent's record, apart from the person's
        self._watch_timer: Timer | None = None
        self._watch_rng = random.Random(0)
        self._watch_wait = 0  # ticks left to show a finished episode
        self.recording_label = ""  # e.g. "games.jsonl" while the person's games are recorded

    # --- layout ------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield Static(id="play-title")
        self.board = board_class(self.session.game.board)()
        self._boards[type(self.board)] = self.board
        yield self.board
        yield StatusLines("play", "hint")
        yield Static(id="play-tally")
        yield Scoreboard(id="play-scoreboard")

    def on_mount(self) -> None:
        self.reload()

    def on_show(self) -> None:
        """Shown again (e.g. back from the Train view): the agent may have learned, so
        the scoreboard and the advice's word on the agent are read afresh, together."""
        self.refresh_agent_figures()
        if not self.watching:
            self._show_status()

    def on_hide(self) -> None:
        self.stop_watching(restore=True)

    @property
    def play_seed(self) -> int:
        return self.app.play_seed  # type: ignore[attr-defined, no-any-return]

    # --- what the app calls --------------------------------------------------
    def reload(self) -> None:
        """Show the session's game: the person's play put away on it (`put_away`) when
        the game and its wrappers are still the same, else a new game, tally and board."""
        session = self.session
        self.stop_watching(restore=False)
        self._agent_exact.drop()  # the figures of what was played before never show
        self.agent_figures, self._exact_reason = None, COMPUTING
        chain, kept = self._kept.pop(session.game.name, ((), None))
        if kept is not None and (kept["game"].session is not session or chain != _chain(session)):
            _close(kept["game"], kept["agent_game"])
            kept = None
        _close(self.game, self.agent_game)
        if kept is None:
            self.game = HumanGame(session, seed=self.play_seed)
            self.game.recorder = getattr(self.app, "recording", None)  # records while switched on
            self.scorecard = Scorecard(tally=self.game.tally)
            self.agent_game = None
            self.agent_card = Scorecard()
            self._watch_rng = random.Random(self.play_seed)
            self.outcomes = {}
        else:
            for name, value in kept.items():
                setattr(self, name, value)
        kind = board_class(session.game.board)
        if type(self.board) is not kind:
            old = self.board
            had_focus = old is not None and old.has_focus
            self.board = self._boards.get(kind)
            if self.board is None:
                self.board = self._boards[kind] = kind()
                self.mount(self.board, before=self.query_one("#play-status"))
            self.board.display = True
            if old is not None:
                old.display = False  # kept for the next game of its kind
            if had_focus:
                self.call_after_refresh(self.focus_board)
        self._show_title()
        if kept is None:
            self._start_episode()
        else:
            self.board.start_episode()
            self._show_board()
            self._show_status()
            self._show_tally()
        self.refresh_agent_figures()

    def put_away(self) -> None:
        """Keep the person's game and record on this game (before a switch to another
        game): `reload` on this game again brings them back as they were."""
        self.stop_watching(restore=False)
        game = self.game
        if game is None:
            return
        self._kept[game.game.name] = (
            _chain(game.session), {name: getattr(self, name) for name in _KEPT_ATTRIBUTES})
        self.game = self.agent_game = None

    def focus_board(self) -> None:
        if self.board is not None and self.board.is_mounted:
            self.board.focus()

    def key_help(self) -> list[tuple[str, str]]:
        """(key, what it does) for playing the current game."""
        keys = self.board.key_help() if self.board is not None else []
        if self.board is not None and self.board.takes_key("a"):
            watch = ("A", "watch the agent play (a is a move here); any key takes over")
        else:
            watch = ("a / A", "watch the agent play; any key takes over")
        return [
            *keys, ("c", "coach: after each move, was it optimal and what did it cost"),
            ("i", "advice: what the exact optimum and the agent would do here"), watch,
        ]

    # --- playing -------------------------------------------------------------
    def on_board_act(self, message: Board.Act) -> None:
        message.stop()
        if not self.watching:
            self.act(message.action)

    def on_board_new_episode(self, message: Board.NewEpisode) -> None:
        """Deal or reset; not in the middle of an episode when the board says so."""
        message.stop()
        game, board = self.game, self.board
        if self.watching or game is None or board is None:
            return
        if not game.done and not board.RESTART_ANYTIME:
            self._say_hint(board.unfinished_hint)
            return
        self._start_episode()

    def on_board_take_over(self, message: Board.TakeOver) -> None:
        """A click on the board while the agent plays: control comes back, nothing moves."""
        message.stop()
        self.stop_watching()

    def act(self, action: str) -> None:
        """Make a move by its action name; a move that cannot be made now only says why."""
        game, board = self.game, self.board
        if game is None or board is None:
            return
        if game.done:
            self._say_hint(board.over_hint)
            return
        before = self._advice(game)  # always: agreement counts whether or not the coach is on
        scene_before = game.scene()
        try:
            step = game.step(action)
        except PlayError as exc:
            self._say_hint(f"That move cannot be made: {exc}.")
            return
        except Exception as exc:  # a wrapper or env refused: say so, keep the app alive
            self._say_hint(f"The env refused the move: {exc}")
            return
        self._hint = ""
        rules = game.game
        agreed = self.scorecard.judge_move(before.optimal if before else (), step.action)
        self._verdict = ""
        if self.show_advice and not self.coach_on:
            self._verdict = _verdict(before, step, rules.action_names)
        self._coach, self._coach_tone = "", ""
        if before is not None and step.action is not None and agreed is not None:
            self._coach = rules.narrator.coach_text(before, step.action, scene_before, game.scene())
            self._coach_tone = "-good" if agreed else "-bad"
        elif before is not None and before.unwrapped_optimal:  # no optimum to judge against
            self._coach = "no verdict: " + before.note
        if step.done:
            word = rules.narrator.tally_word(step)
            self.outcomes[word] = self.outcomes.get(word, 0) + 1
            self.scorecard.add_figures(rules.narrator.episode_figures(step, game.first_info))
            self._headline = Content(
                rules.narrator.outcome_text(step, game.first_info, game.scene())
            )
            self._tone = "-even" if not step.terminated else _tone(step.reward)
        else:
            self._headline = Content(f"{action.capitalize()}: reward {format_reward(step.reward)}")
            self._tone = ""
        self._show_board()
        self._show_status()
        self._show_tally()
        if step.done:
            self.refresh_agent_figures()
        else:
            self._show_scoreboard()

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
            noun = game.game.episode_noun
            self._headline = Content.from_markup(
                f"New {escape(noun)}.  [not bold $text-muted]{escape(board.prompt)}[/]"
            )
            self._tone = ""
        self._verdict = ""
        self._coach, self._coach_tone = "", ""
        board.start_episode()
        self._show_board()
        self._show_status()
        self._show_tally()

    # --- drawing ---------------------------------------------------------------
    def _show_board(self, game: HumanGame | None = None) -> None:
        """Draw `game` (the person's when None) on the board."""
        game, board = self.game if game is None else game, self.board
        if game is None or board is None:
            return
        board.show_scene(game.scene(), reveal=game.done)
        board.set_episode_over(game.done)

    def _show_title(self) -> None:
        session = self.session
        chain = " → ".join(_short(choice.name, choice.params) for choice in session.applied)
        title = f"[b]{escape(session.game.title)}[/]  [$text-muted]wrappers:[/] " + (
            f"[i $text-accent]{escape(chain)}[/]" if chain else "[$text-muted]none[/]"
        )
        modes = [mode for mode, (attribute, _) in MODES.items() if getattr(self, attribute)]
        if modes:
            title += "  [$text-success]" + escape(" · ".join(f"{m} on" for m in modes)) + "[/]"
        if self.recording_label:
            title += f"  [b $text-error]● REC[/] [$text-muted]{escape(self.recording_label)}[/]"
        content = Content.from_markup(title)
        widget = self.query_one("#play-title", Static)
        widget.update(content)
        widget.tooltip = content.plain  # the line is cut short on a narrow screen

    def show_recording(self, label: str) -> None:
        """Say in the title that the person's games are being recorded ('' when not)."""
        self.recording_label = label
        self._show_title()

    def _say_hint(self, hint: str) -> None:
        self._hint = hint
        self._show_status()

    def _show_status(self) -> None:
        game = self.game
        last = game.last if game is not None else None
        detail = ""
        if game is not None and last is not None:
            parts = [self._verdict] if self._verdict else []
            # In the game's words, or raw (cut short) when wrappers reshaped it.
            seen = game.game.states.describe(last.observation, self.session.env_kwargs)
            parts.append(f"observation: {cut(seen, OBSERVATION_CHARS)}")
            progress = game.game.narrator.progress_text(last, game.first_info)
            if progress:
                parts.append(progress)
            if last.steps:
                parts.append(f"return {format_reward(last.episode_return)}")
            if self.show_advice and not game.done:
                advice = self._advice(game)
                parts.append(advice.note if advice is not None else "no advice here")
                parts.append(self.agent_note(last.observation))
            detail = "  ·  ".join(parts)
        coach = self._coach if self.coach_on else ""
        self.query_one(StatusLines).show(self._headline, detail, coach, self._coach_tone,
                                         self._tone, hint=self._hint)

    def _advice(self, game: HumanGame) -> Advice | None:
        """What the exact optimum would do now in `game` (None when the game cannot say)."""
        if game.done:
            return None
        return game.game.oracle.advice(game.env, self.session.env_kwargs)

    def agent_note(self, observation: Any) -> str:
        """'agent: hit (Q stick −0.310, hit −0.402)': the greedy agent's choice here."""
        names = self.session.game.action_names
        choice = self.session.greedy_actions_for(observation, self._training_snapshot())
        if choice is None:
            return "agent: has never seen this state (it would pick at random)"
        ties, q = choice
        if len(ties) == len(q) > 1:  # every action ties: what it does is a coin toss
            return "agent: no preference here (it would pick at random)"

        def name(a: int) -> str:
            return names[a] if a < len(names) else str(a)

        values = ", ".join(f"{name(a)} {signed(float(v), 3)}" for a, v in enumerate(q))
        return f"agent: {' or '.join(name(a) for a in ties)} (Q {values})"

    def action_mode(self, mode: str) -> None:
        """Switch one of the `MODES` on or off."""
        attribute, said = MODES[mode]
        on = not getattr(self, attribute)
        setattr(self, attribute, on)
        self._verdict = ""
        self._show_title()
        if not self.watching:
            self._show_status()
        self.notify(said if on else f"{mode.capitalize()} off.", timeout=3)

    # --- the scoreboard --------------------------------------------------------
    def refresh_agent_figures(self) -> None:
        """Redraw the scoreboard and have the agent's exact figures computed afresh off the
        event loop; the scoreboard shows them when they come."""
        self._show_scoreboard()
        self._agent_exact.ask((self.session.detached(), self._training_snapshot()))

    @on(LatestOnly.Computed)
    def _agent_figures_computed(self, message: LatestOnly.Computed) -> None:
        message.stop()
        result = self._agent_exact.done(message)
        if result is not None:
            self.agent_figures, self._exact_reason = result
            self._show_scoreboard()

    @property
    def agent_figures_shown(self) -> bool:
        """Whether the scoreboard shows the agent's figures as last asked, none to come."""
        return self._agent_exact.idle and self._exact_reason != COMPUTING

    def _training_snapshot(self) -> TrainingSnapshot | None:
        """While training runs, its latest snapshot: the freshest table whatever the
        runner (a child process hands the agent itself back only when paused)."""
        runner = getattr(self.app, "runner", None)
        return runner.latest if runner is not None and runner.running else None

    def _show_scoreboard(self) -> None:
        """The scoreboard's rows as the game's narrator words them."""
        if not self.is_mounted:
            return
        session = self.session
        watched = self.agent_card if self.agent_card.tally.episodes else None
        scope = session.game.oracle.scope(session.env_kwargs, session.changes)
        self.query_one(Scoreboard).show_rows(session.game.narrator.scoreboard(
            self.scorecard, self.agent_figures, watched, self._exact_reason, scope))

    # --- watching the agent ----------------------------------------------------
    def action_watch_agent(self) -> None:
        """Let the greedy agent play fresh episodes on the board until a key is pressed."""
        board = self.board
        if board is None or self.watching:
            return
        session = self.session
        if self.agent_game is None:
            try:
                self.agent_game = HumanGame(session, seed=self.play_seed + WATCH_SEED_OFFSET)
            except Exception as exc:
                self._say_hint(f"The agent cannot play here: {exc}")
                return
            self.agent_card = Scorecard(tally=self.agent_game.tally)
        self.watching = True
        self._hint = ""
        board.set_agent_playing(True)
        self.focus_board()
        if not self._agent_new_episode():
            return
        self._watch_timer = self.set_interval(self.watch_interval, self._watch_tick)

    def stop_watching(self, restore: bool = True) -> None:
        """Stop the agent; with `restore`, the person's game comes back on the board."""
        if self._watch_timer is not None:
            self._watch_timer.stop()
            self._watch_timer = None
        if not self.watching:
            return
        self.watching = False
        board, game = self.board, self.game
        if board is None:
            return
        board.set_agent_playing(False)
        board.start_episode()
        if not restore or game is None:
            return
        noun = escape(game.game.episode_noun)
        hint = board.over_hint if game.done else board.prompt
        self._headline = Content.from_markup(
            f"Back to your {noun}.  [not bold $text-muted]{escape(hint)}[/]"
        )
        self._tone = ""
        self._show_board()
        self._show_status()

    def on_key(self, event: events.Key) -> None:
        """While the agent plays, any key takes over (and does nothing else)."""
        if self.watching:
            event.stop()
            event.prevent_default()
            self.stop_watching()

    def on_descendant_blur(self, event: events.DescendantBlur) -> None:
        if self.watching and event.widget is self.board:  # the keyboard went elsewhere
            self.stop_watching()

    def _agent_new_episode(self) -> bool:
        game, board = self.agent_game, self.board
        if game is None or board is None:
            return False
        try:
            game.reset()
        except Exception as exc:
            self.stop_watching()
            self._say_hint(f"The agent's episode could not start: {exc}")
            return False
        board.start_episode()
        self._show_agent(f"New {game.game.episode_noun} for the agent.")
        return True

    def _watch_tick(self) -> None:
        """One move of the watched agent (or the pause after an episode, or a new one)."""
        game = self.agent_game
        if not self.watching or game is None:
            return
        if game.done:
            if self._watch_wait > 0:
                self._watch_wait -= 1
            else:
                self._agent_new_episode()
            return
        session = self.session
        before = self._advice(game)
        assert game.last is not None
        choice = session.greedy_actions_for(game.last.observation, self._training_snapshot())
        ties = choice[0] if choice is not None else tuple(range(session.agent.n_actions))
        action = ties[0] if len(ties) == 1 else ties[self._watch_rng.randrange(len(ties))]
        note = self.agent_note(game.last.observation)
        try:
            step = game.step(action)
        except Exception as exc:  # a wrapper or env refused: stop and say why
            self.stop_watching()
            self._say_hint(f"The env refused the agent's move: {exc}")
            return
        self.agent_card.judge_move(before.optimal if before else (), step.action)
        name = game.game.action_names[action]
        if step.done:
            self.agent_card.add_figures(game.game.narrator.episode_figures(step, game.first_info))
            self._watch_wait = self.watch_pause_ticks
            moves = plural(step.steps, "move")
            self._show_agent(
                f"The agent's {game.game.episode_noun} is over: "
                f"return {format_reward(step.episode_return)} after {moves}.",
                tone=_tone(step.episode_return) if step.terminated else "-even",
            )
            self.refresh_agent_figures()
        else:
            self._show_agent(f"The agent chose {name}: {note.removeprefix('agent: ')}.")

    def _show_agent(self, detail: str, tone: str = "-agent") -> None:
        if self.agent_game is None or self.board is None:
            return
        self._show_board(self.agent_game)
        self._hint = ""
        self.query_one(StatusLines).show(Content(WATCHING), detail, tone=tone)

    def _show_tally(self) -> None:
        game = self.game
        if game is None:
            return
        tally = game.tally
        parts = [
            f"[$text-muted]{escape(game.game.episode_noun.capitalize())}s[/] "
            f"[b]{tally.episodes}[/]"
        ]
        for word in game.game.narrator.tally_words:
            count = self.outcomes.get(word.label, 0)
            if not (count or word.always):
                continue
            colour = TONE_COLOURS.get(word.tone, "")
            style = f"b {colour}" if count and colour else "b"
            parts.append(f"[$text-muted]{escape(word.label)}[/] [{style}]{count}[/]")
        mean = "[$text-muted]–[/]"
        if tally.episodes:
            mean = f"[b]{format_reward(round(tally.mean, 3))}[/]"
            mean += f" ± {interval_text(tally)} [$text-muted](95% CI)[/]"
        parts.append(f"[$text-muted]mean return[/] {mean}")
        self.query_one("#play-tally", Static).update(Content.from_markup("   ".join(parts)))


def _close(*games: HumanGame | None) -> None:
    for game in games:
        if game is not None:
            game.close()


def _verdict(before: Advice | None, step: PlayStep, names: tuple[str, ...]) -> str:
    """'✓ optimal' or '✗ the optimum: stick' for the move just made ('' without advice)."""
    if before is None or not before.optimal or step.action is None:
        return ""
    if step.action in before.optimal:
        return "✓ optimal move"
    return "✗ the optimum: " + " or ".join(names[a] for a in before.optimal)


def _tone(reward: float) -> str:
    return "-good" if reward > 0 else "-bad" if reward < 0 else "-even"


def _short(name: str, params: tuple[tuple[str, Any], ...]) -> str:
    """A wrapper in a few characters: `TimeLimit(3)`, `StickyAction(0.25)`."""
    if not params:
        return name
    return f"{name}({', '.join(str(value) for _, value in params)})"
