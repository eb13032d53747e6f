"""What a game profile is: everything that differs per game, in one place.

Front ends never branch on a game's name; they ask the profile: action names
and keys, how a state reads as text, which base states the heatmaps and the
exact reference look at, how a finished episode is scored, how a coach words
a move, and what a scoreboard says about a player, the agent and the optimum.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from tui_gym.core.agent import Hyperparameters
from tui_gym.core.heatmap import Heatmap
from tui_gym.core.params import Param
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges

if TYPE_CHECKING:
    from tui_gym.core.play import PlayStep, Scorecard, Tally


@dataclass(frozen=True)
class Scope:
    """Whether a game's exact figures describe the game as it is played (with its
    wrappers), and a note for people when there is something to say: which
    wrappers they take into account, or that they are figures of the unwrapped
    game because a wrapper changes it in a way they cannot follow."""

    exact: bool = True
    note: str = ""


EXACT = Scope()
MIN_CI_EPISODES = 30  # episodes before a mean's 95% interval is shown (normal approximation)


@dataclass(frozen=True)
class ReferenceMetrics:
    """How the agent's greedy policy compares with the exact optimum."""

    figures: dict[str, float]  # e.g. exact_value / optimal_value / gap, or optimal_pair_fraction
    summary: str  # one line for people
    scope: Scope = EXACT  # whether the figures are of the game as played


@dataclass(frozen=True)
class Advice:
    """What the exact optimum would do in the env's current state.

    `optimal` and `values` are for the game as played, wrappers included;
    when the wrappers change it in a way the exact figures cannot follow,
    both are empty and `unwrapped_optimal` holds the unwrapped game's optimum
    (the note says so), so nothing claims an optimum that may not be one.
    """

    optimal: tuple[int, ...]  # every optimal action (empty when there is no decision)
    values: dict[int, float] | None = None  # exact expected return per action, when known
    note: str = ""  # one line for people
    unwrapped_optimal: tuple[int, ...] = ()  # the unwrapped game's optimum, when not exact


class ScoreRow(NamedTuple):
    """One line of a scoreboard: who ("You", "Agent", "Optimum", "Watched") and how,
    in full and in a few words (`short`, for narrow screens; the full text if empty)."""

    who: str
    text: str
    short: str = ""


@dataclass(frozen=True)
class EvalOutcome:
    """Per-game extras of a greedy evaluation, beside mean and std of return."""

    figures: dict[str, float] = field(default_factory=dict)


class GameProfile(ABC):
    """The per-game knowledge every front end relies on."""

    name: str  # short alias, e.g. "blackjack"
    title: str  # for people, e.g. "Blackjack"
    env_id: str  # the Gymnasium id it plays
    other_ids: tuple[str, ...] = ()  # further ids of the same game
    action_names: tuple[str, ...] = ()
    description: str = ""

    def matches(self, env_id: str) -> bool:
        return env_id in (self.env_id, *self.other_ids)

    def default_kwargs(self) -> dict[str, Any]:
        """Env arguments the game starts with."""
        return {p.name: p.default for p in self.env_params}

    def default_hyperparameters(self) -> Hyperparameters:
        """Hyperparameters that learn this game well (see the README)."""
        return Hyperparameters()

    def normalize_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """Check and complete env arguments; ValueError with a clear message when wrong."""
        params = {p.name: p for p in self.env_params}
        out = self.default_kwargs()
        for key, value in kwargs.items():
            if key not in params:
                known = ", ".join(params) or "no arguments"
                raise ValueError(f"{self.title} takes {known}, not {key!r}")
            out[key] = params[key].parse(value)
        return out

    def action_index(self, action: int | str) -> int:
        """An action given as its number or its name (case-insensitive)."""
        if isinstance(action, bool):
            raise ValueError(f"invalid action {action!r}")
        if isinstance(action, int | np.integer):
            if 0 <= int(action) < len(self.action_names):
                return int(action)
        elif isinstance(action, str):
            text = action.strip().lower()
            if text in self.action_names:
                return self.action_names.index(text)
            # ASCII digits only ('١' and '²' are digits to Python, not to the protocol).
            if text.isascii() and text.isdigit() and int(text) < len(self.action_names):
                return int(text)
        names = ", ".join(f"{i}={n}" for i, n in enumerate(self.action_names))
        raise ValueError(f"invalid action {action!r}; valid actions: {names}")

    @abstractmethod
    def base_observations(self, env_kwargs: Mapping[str, Any]) -> list[Any]:
        """Every state of the bare env that heatmaps and the exact reference look at."""

    @abstractmethod
    def reference(
        self, q: np.ndarray, env_kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics:
        """Exact comparison of the greedy policy of `q` (rows: base states) with the optimum,
        in the game as the wrappers (`changes`) make it where `scope` says it can be.

        The greedy policy breaks ties at random, as the agent does: a state whose
        actions tie (an unvisited one, all zeros) counts as a uniform choice."""

    @abstractmethod
    def heatmaps(
        self,
        q: np.ndarray,
        env_kwargs: Mapping[str, Any],
        focus: Any = None,
        changes: GameChanges = NO_CHANGES,
    ) -> list[Heatmap]:
        """Heatmap panels for `q` (rows = base_observations); `focus` picks e.g. a target."""

    def scope(self, env_kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Scope:
        """Whether the exact figures can follow what the wrappers change (see `Scope`)."""
        if changes.others:
            return Scope(False, unwrapped_note(changes.others))
        return EXACT

    @abstractmethod
    def describe(self, observation: Any) -> str:
        """The state in words, e.g. 'sum 15 vs dealer 10, no usable ace'."""

    @abstractmethod
    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        """Per-game figures from a greedy evaluation's episodes."""

    def episode_detail(
        self, first_info: Mapping[str, Any], length: int, total: float, terminated: bool
    ) -> dict[str, Any]:
        """What eval_outcome needs to remember of one episode."""
        return {"length": length, "return": total, "terminated": terminated}

    env_params: tuple[Param, ...] = ()  # the env's arguments a person may change
    # Heatmaps that follow a chosen cell (GridWorld: the target). Games without
    # one keep the defaults below; a front end asks before offering to move it.
    heatmap_focus: bool = False

    def default_heatmap_focus(self, env_kwargs: Mapping[str, Any]) -> Any:
        """The focus the heatmaps start with (None when the game has no focus)."""
        return None

    def heatmap_focus_at(self, row: int, col: int, env_kwargs: Mapping[str, Any]) -> Any:
        """The focus that heatmap cell (row, col) stands for (None when there is none)."""
        return None

    def heatmap_focus_cell(
        self, focus: Any, env_kwargs: Mapping[str, Any]
    ) -> tuple[int, int] | None:
        """The heatmap cell (row, col) of a focus; the inverse of `heatmap_focus_at`."""
        return None

    board: str = ""  # which kind of board draws this game's scene ("cards", "grid")
    action_keys: dict[str, str] = {}  # keyboard key -> action name, for people

    render_mode: str | None = None  # the env's text render mode, if it has one
    episode_noun: str = "episode"  # what people call one episode, e.g. "hand"

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        """How a finished episode ended, in plain words (truncation told apart)."""
        steps = f"{last.steps} step{'' if last.steps == 1 else 's'}"
        total = format_reward(last.episode_return)
        if last.terminated:
            return f"Episode over after {steps}, return {total}"
        return f"Truncated by the time limit after {steps}, return {total}"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        """How far the running episode has got, for people ('' when nothing to say)."""
        return ""

    @abstractmethod
    def scene(self, env: Any) -> dict[str, Any]:
        """What a board needs to draw the env's current state (plain data, a copy)."""

    @abstractmethod
    def advice(self, env: Any, env_kwargs: Mapping[str, Any]) -> Advice:
        """The optimal action(s) in the env's current state, in the game as its
        wrappers make it (read from `env`); see `Advice` for when they cannot say."""

    # --- coaching and the scoreboard ----------------------------------------
    def coach_text(
        self,
        before: Advice,
        action: int,
        scene_before: Mapping[str, Any],
        scene_after: Mapping[str, Any],
    ) -> str:
        """One line judging `action`, taken where `before` was the advice ('' without a decision).

        The default words it by the exact values when the advice has them
        ("✗ hit cost 0.123 in expected return (stick: −0.290, hit: −0.413)").
        """
        if not before.optimal:
            return ""
        name = self.action_names[action]
        if action in before.optimal:
            return f"✓ {name} was optimal"
        if before.values and action in before.values:
            cost = max(before.values.values()) - before.values[action]
            values = ", ".join(
                f"{self.action_names[a]}: {signed(v, 3)}" for a, v in sorted(before.values.items())
            )
            return f"✗ {name} cost {cost:.3f} in expected return ({values})"
        best = " or ".join(self.action_names[a] for a in before.optimal)
        return f"✗ {name} was not optimal (the optimum: {best})"

    def episode_figures(self, last: PlayStep, first_info: Mapping[str, Any]) -> dict[str, float]:
        """Figures of one finished episode that a scoreboard averages (none by default)."""
        return {}

    def agent_figures(
        self,
        q: np.ndarray | None,
        env_kwargs: Mapping[str, Any],
        changes: GameChanges = NO_CHANGES,
    ) -> dict[str, float]:
        """Exact figures for the scoreboard: of the greedy policy of `q` (rows = base
        states; None when wrappers hide them; ties broken at random, as the agent
        does) and of the optimum. A few ms at most."""
        return {}

    def scoreboard(
        self,
        you: Scorecard,
        figures: Mapping[str, float] | None,
        watched: Scorecard | None = None,
        agent_note: str = "",
        scope: Scope = EXACT,
    ) -> list[ScoreRow]:
        """The scoreboard's rows: the person (`you`), the agent (exact `figures` from
        `agent_figures`, or `agent_note` saying why there are none), the optimum,
        and the agent's episodes watched on the board; `scope` says whether the
        exact figures are of the game as played."""
        rows = [
            ScoreRow(
                "You",
                join_parts(return_summary(you.tally, self.episode_noun), agreement_summary(you)),
                join_parts(
                    return_summary(you.tally, self.episode_noun, short=True),
                    agreement_summary(you, short=True),
                ),
            ),
            ScoreRow("Agent", agent_note or "no exact figures for this game", "–"),
        ]
        if watched is not None and watched.tally.episodes:
            rows.append(watched_row(watched, self.episode_noun))
        return rows

    def text(self, env: Any, reveal: bool = True) -> str:
        """A plain-text picture of the env's state."""
        picture = env.render() if self.render_mode == "ansi" else None
        return picture if isinstance(picture, str) else ""

    def json_observation(self, observation: Any) -> Any:
        """The observation as JSON-friendly data."""
        return to_jsonable(observation)


def to_jsonable(value: Any) -> Any:
    """Numpy arrays, numbers, tuples and dicts as plain JSON data."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_jsonable(v) for v in value]
    return value


def format_reward(value: float) -> str:
    """A reward for people: '+1', '−1' (a true minus sign), '0', '+1.5'."""
    if value == 0:
        return "0"
    text = f"{abs(value):.4g}"
    return ("+" if value > 0 else "\u2212") + text


def signed(value: float, places: int) -> str:
    """A number with its sign for people: '+0.125', '−0.290' (a true minus), '0.000'."""
    text = f"{abs(value):.{places}f}"
    if float(text) == 0:
        return text
    return ("+" if value > 0 else "\u2212") + text


def plural(count: int, noun: str) -> str:
    """'1 hand', '3 hands'."""
    return f"{count} {noun}{'' if count == 1 else 's'}"


def return_summary(tally: Tally, noun: str, short: bool = False) -> str:
    """'mean return −0.125 ± 0.412 (95% CI) over 38 hands' or 'no hands played yet';
    `short`: '−0.125 ± 0.412 over 38 hands'. Below `MIN_CI_EPISODES` the
    interval shows as '–' (a handful of hands says little about its width)."""
    if not tally.episodes:
        return f"no {noun}s yet" if short else f"no {noun}s played yet"
    text = signed(tally.mean, 3) if short else f"mean return {signed(tally.mean, 3)}"
    text += " ± " + interval_text(tally) + ("" if short else " (95% CI)")
    return f"{text} over {plural(tally.episodes, noun)}"


def interval_text(tally: Tally) -> str:
    """The half-width of the 95% interval of the mean return ('0.412'), or '–' while
    fewer than `MIN_CI_EPISODES` episodes make it."""
    low, high = tally.confidence_interval(min_episodes=MIN_CI_EPISODES)
    return "–" if low != low else f"{(high - low) / 2:.3f}"  # NaN: too few episodes


def agreement_summary(
    card: Scorecard, words: str = "moves as the optimum", short: bool = False
) -> str:
    """'9/11 moves as the optimum (82%)', `short` '82% optimal' ('' before a decision)."""
    if card.agreement is None:
        return ""
    if short:
        return f"{card.agreement:.0%} optimal"
    return f"{card.agreed}/{card.decisions} {words} ({card.agreement:.0%})"


def watched_row(
    card: Scorecard, noun: str, words: str = "moves as the optimum", extra: str = ""
) -> ScoreRow:
    """What the agent did while a person watched: episodes, mean return, agreement."""
    tally = card.tally
    text = f"the agent played {plural(tally.episodes, noun)}, mean return {signed(tally.mean, 3)}"
    short = f"agent: {plural(tally.episodes, noun)}, {signed(tally.mean, 3)}"
    return ScoreRow(
        "Watched",
        join_parts(text, agreement_summary(card, words), extra),
        join_parts(short, extra),
    )


def join_parts(*parts: str) -> str:
    """Non-empty parts joined with " · "."""
    return " · ".join(part for part in parts if part)


def greedy_policy(q: np.ndarray) -> np.ndarray:
    """Greedy action per row; ties go to the lowest action (deterministic, for exact scoring)."""
    return np.argmax(q, axis=1).astype(np.int64)


def greedy_probabilities(q: np.ndarray) -> np.ndarray:
    """Each action's chance per row under the greedy policy as the agent plays it:
    ties (e.g. an unvisited state's zeros) broken uniformly at random."""
    q = np.asarray(q, dtype=np.float64)
    tied = q == q.max(axis=1, keepdims=True)
    return tied / tied.sum(axis=1, keepdims=True)


def all_tied(q: np.ndarray) -> np.ndarray:
    """Per row: whether every action ties (the agent has no preference there)."""
    q = np.asarray(q)
    return (q == q[:, :1]).all(axis=1)


def unwrapped_note(names: tuple[str, ...] | list[str]) -> str:
    """'figures of the unwrapped game: StickyAction changes it'."""
    verb = "changes" if len(names) == 1 else "change"
    return f"figures of the unwrapped game: {', '.join(names)} {verb} it"
