"""What a game is: its identity and parameters, and four small roles."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numpy as np
import numpy.typing as npt

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.params import Param, shown_value
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.games.words import (
    ScoreRow,
    agreement_summary,
    format_reward,
    join_parts,
    plural,
    return_summary,
    signed,
    to_jsonable,
    watched_row,
)

if TYPE_CHECKING:
    from tui_gym.core.mdp import FiniteMDP
    from tui_gym.games.planning import PlanModel
    from tui_gym.session.play import PlayStep, Scorecard

__all__ = [
    "EXACT", "Advice", "Bound", "EvalOutcome", "Game", "HeatmapLayout", "Narrator", "NotAvailable",
    "Oracle", "ReachNarrator", "ReferenceMetrics", "Scope", "StateSpace", "TallyWord",
    "TrainingModel",
]

BoolArray = npt.NDArray[np.bool_]

# What a state that cannot be read counts as: the reasons a role may meet, never a bug's.
UNREADABLE = (TypeError, ValueError, KeyError, IndexError, AttributeError)


# --- the data roles hand out ------------------------------------------------------


@dataclass(frozen=True)
class Scope:
    """Whether a game's exact figures describe the game as played (wrappers included),
    and a note for people saying which wrappers they follow, or which they cannot."""

    exact: bool = True
    note: str = ""


EXACT = Scope()


@dataclass(frozen=True)
class ReferenceMetrics:
    """How the agent's greedy policy compares with the exact optimum."""

    figures: dict[str, float]  # e.g. exact_value / optimal_value / gap
    summary: str  # one line for people
    scope: Scope = EXACT  # whether the figures are of the game as played


@dataclass(frozen=True)
class Advice:
    """What the exact optimum would do in the env's current state, wrappers included;
    where they change the game beyond the exact figures, only `unwrapped_optimal`. `equal`:
    actions worth as much that waste a step while time remains."""

    optimal: tuple[int, ...]  # every optimal action (empty when there is no decision)
    values: dict[int, float] | None = None  # exact expected return per action, when known
    note: str = ""  # one line for people
    unwrapped_optimal: tuple[int, ...] = ()  # the unwrapped game's optimum, when not exact
    equal: tuple[int, ...] = ()


class TallyWord(NamedTuple):
    """One count of the Play view's running tally: its label, the tone of a count
    above zero ("good", "even", "bad" or "" for none), and whether it shows at zero."""

    label: str
    tone: str = ""
    always: bool = True


@dataclass(frozen=True, eq=False)
class TrainingModel:
    """A game's model as the wrappers make it, for the engine: `rows`, the table row of
    each model state (None: row s); `later`, each later phase's (start step, model)."""

    model: FiniteMDP
    rows: np.ndarray | None = None
    later: tuple[tuple[int, FiniteMDP], ...] = ()


@dataclass(frozen=True)
class EvalOutcome:
    """Per-game extras of a greedy evaluation, beside mean and std of return."""

    figures: dict[str, float] = field(default_factory=dict)


# --- the roles ---------------------------------------------------------------------


class Role:
    """A part of a game; `game` gives it the game's names and parameters."""

    def __init__(self, game: Game) -> None:
        self.game = game


class StateSpace(Role):
    """The game's states: which ones the heatmaps and exact figures look at, and how
    one reads in words, on a board (`scene`) and as text."""

    def base_observations(self, kwargs: Mapping[str, Any]) -> list[Any] | NotAvailable:
        """Every state of the bare env the heatmaps and the exact figures look at."""
        return NotAvailable(f"{self.game.title} lists no states")

    def describe(self, observation: Any, kwargs: Mapping[str, Any] | None = None) -> str:
        """The state in words ('row 2, col 3'); the raw observation when it cannot say.
        `kwargs`, the game's arguments, when the words depend on them (a map's size)."""
        try:
            return self.describe_state(observation, kwargs or self.game.default_kwargs())
        except UNREADABLE:
            return str(to_jsonable(observation))

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        """`describe`'s words; may raise for an observation of another shape."""
        return str(to_jsonable(observation))

    def scene(self, env: Any, before: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """What the game's board draws of the env's state (plain data, a copy; empty before the
        first reset); `before`, the scene before the last move, tells what the move did."""
        try:
            return self.read_scene(env.unwrapped, before or {})
        except UNREADABLE:
            return {}

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        """`scene` of the unwrapped env; may raise before the first reset."""
        return {}

    def text(self, env: Any, reveal: bool = True, before: Mapping[str, Any] | None = None) -> str:
        """A plain-text picture of the env's state ('' when it has none); `reveal` shows
        what is hidden during an episode, `before` is as for `scene`."""
        return ansi_text(env) if self.game.render_mode == "ansi" else ""

    def json_observation(self, observation: Any) -> Any:
        """The observation as JSON-friendly data."""
        return to_jsonable(observation)


class Oracle(Role):
    """The exact figures: the optimum, a policy's distance from it, the optimal actions."""

    def scope(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Scope:
        """Whether the exact figures follow what the wrappers change (see `Scope`)."""
        return Scope(False, "no exact figures for this game")

    def reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        """The greedy policy of `q` (rows: base states; ties at random) beside the optimum,
        in the game as the wrappers make it where `scope` says it can be."""
        return NotAvailable(f"{self.game.title} has no exact optimum")

    def evaluation_reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        """What an evaluation reports: `reference`, plus exact figures too costly for
        every redraw of a running view (none beyond it by default)."""
        return self.reference(q, kwargs, changes)

    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        """The optimal action(s) in the env's current state, wrappers read from `env`."""
        return Advice((), None, "no exact optimum for this game")

    def agent_figures(
        self, q: np.ndarray | None, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> dict[str, float]:
        """Exact figures for the scoreboard: of the greedy policy of `q` (None when
        wrappers hide the base states) and of the optimum; none when there are none."""
        return {}

    def optimal_marks(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> BoolArray | NotAvailable:
        """`[base states, actions]`: the actions a heatmap does not mark with `*`."""
        return NotAvailable(f"{self.game.title} has no exact optimum")

    def optimum(self, kwargs: Mapping[str, Any]) -> Optimum | NotAvailable:
        """The optimum of the unwrapped game, for `tui-gym optimal`."""
        return NotAvailable(f"{self.game.title} has no exact optimum")

    def fixed_policy_bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> FixedBound | NotAvailable:
        """How close any fixed (greedy) policy gets to the optimum, when it may not
        reach it (an episode limit rewards playing differently as time runs out)."""
        return NotAvailable(f"{self.game.title} has no exact optimum")

    def return_range(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> tuple[float, float] | NotAvailable:
        """The lowest and the highest return one episode can have, in the game as the
        wrappers make it (±inf on a side with no bound): what a chart never shows beyond."""
        return NotAvailable(f"{self.game.title} has no exact model")

    def bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> Bound | NotAvailable:
        """What training with the game's default hyperparameters reaches, as a figure
        of `reference` and its limit (the bound the README and the tests state)."""
        return NotAvailable(f"{self.game.title} states no bound")


@dataclass(frozen=True)
class Optimum:
    """The optimum of a game for people: its value, what it means, and per base state
    the optimal actions and the value of playing optimally from there."""

    value: float
    summary: str  # one line: what the value is
    q: np.ndarray | None = None  # [base states, actions] optimal action values, when listed
    marks: np.ndarray | None = None  # [base states, actions]: the optimal actions
    figures: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Bound:
    """A figure of `Oracle.reference` and the limit a trained agent's reaches:
    `figure <= limit` for a gap, `figure >= limit` for a share (`at_least`)."""

    figure: str
    limit: float
    text: str  # for people: 'gap <= 0.0074 (1% of the optimum)'
    at_least: bool = False

    def met(self, figures: Mapping[str, float]) -> bool:
        value = figures.get(self.figure)
        if value is None:
            return False
        return value >= self.limit if self.at_least else value <= self.limit + 1e-12


@dataclass(frozen=True)
class FixedBound:
    """The best value a fixed policy was found to reach, beside the optimum."""

    optimal_value: float
    fixed_value: float  # the best fixed policy found (a local search: a lower bound)

    @property
    def shortfall(self) -> float:
        """How far below the optimum the best fixed policy found stays (0 when it reaches it)."""
        return max(0.0, self.optimal_value - self.fixed_value)


class Narrator(Role):
    """The game's words: outcomes, the coach, the tally, the scoreboard, evaluation."""

    agreement_words = "moves as the optimum"

    tally_words: tuple[TallyWord, ...] = (
        TallyWord("wins", "good"), TallyWord("draws", "even"), TallyWord("losses", "bad"),
        TallyWord("truncated", always=False),
    )

    def tally_word(self, last: PlayStep) -> str:
        """The `tally_words` label a finished episode counts under ("episodes" with none)."""
        if not self.tally_words:
            return "episodes"
        if last.truncated and not last.terminated:
            return "truncated"
        if last.episode_return > 0:
            return "wins"
        return "losses" if last.episode_return < 0 else "draws"

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        """How a finished episode ended, in plain words (truncation told apart)."""
        steps, total = plural(last.steps, "step"), format_reward(last.episode_return)
        if last.terminated:
            return f"Episode over after {steps}, return {total}"
        return f"Truncated by the time limit after {steps}, return {total}"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        """How far the running episode has got ('' when nothing to say)."""
        return ""

    def coach_text(
        self, before: Advice, action: int, scene_before: Mapping[str, Any],
        scene_after: Mapping[str, Any],
    ) -> str:
        """One line judging `action`, taken where `before` was the advice ('' without a
        decision), worded by the exact values when the advice has them."""
        if not before.optimal:
            return ""
        names = self.game.action_names
        name = names[action] if 0 <= action < len(names) else str(action)
        if action in before.optimal:
            return f"✓ {name} was optimal"
        best = " or ".join(names[a] for a in before.optimal)
        if action in before.equal:
            return f"✗ {name} keeps the exact value but wastes a step (quicker: {best})"
        if before.values and action in before.values:
            cost = max(before.values.values()) - before.values[action]
            values = ", ".join(
                f"{names[a]}: {signed(v, 3)}" for a, v in sorted(before.values.items())
            )
            return f"✗ {name} cost {cost:.3f} in expected return ({values})"
        return f"✗ {name} was not optimal (the optimum: {best})"

    def episode_figures(self, last: PlayStep, first_info: Mapping[str, Any]) -> dict[str, float]:
        """Figures of one finished episode that a scoreboard averages (none by default)."""
        return {}

    def scoreboard(
        self, you: Scorecard, figures: Mapping[str, float] | None, watched: Scorecard | None = None,
        agent_note: str = "", scope: Scope = EXACT,
    ) -> list[ScoreRow]:
        """The rows: the person's mean return and agreement, the agent's and the optimum's
        exact values (`figures` from `Oracle.agent_figures`, of `scope`), what was watched."""
        figures = figures or {}
        noun = self.game.episode_noun
        words = self.agreement_words
        rows = [
            ScoreRow(
                "You",
                join_parts(return_summary(you.tally, noun), agreement_summary(you, words)),
                join_parts(
                    return_summary(you.tally, noun, short=True), agreement_summary(you, short=True),
                ),
            )
        ]
        places = self.value_places
        if "exact_value" in figures:
            value = signed(figures["exact_value"], places)
            text = f"exact value {value} with its greedy policy"
            if "gap" in figures:
                text += f" ({figures['gap']:.{places}f} below the optimum)"
            rows.append(ScoreRow("Agent", text, f"{value} exact"))
        else:
            rows.append(ScoreRow("Agent", agent_note or "no exact figures for this game", "–"))
        if "optimal_value" in figures:
            value = signed(figures["optimal_value"], places)
            text, short = f"exact value {value}", f"{value} exact"
            if scope.note:
                text += f" ({scope.note})"
            if not scope.exact:
                short = f"{value} unwrapped"
            rows.append(ScoreRow("Optimum", text, short))
        if watched is not None and watched.tally.episodes:
            rows.append(watched_row(watched, noun, words))
        return rows

    value_places = 3  # decimals of the values the scoreboard shows

    def episode_detail(
        self, first_info: Mapping[str, Any], length: int, total: float, terminated: bool
    ) -> dict[str, Any]:
        """What `eval_outcome` needs to remember of one episode."""
        return {"length": length, "return": total, "terminated": terminated}

    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        """Per-game figures from a greedy evaluation's episodes (the share that ended, as
        `ended_figure`)."""
        n = max(1, len(details))
        ended = sum(1 for d in details if d.get("terminated"))
        return EvalOutcome(figures={self.ended_figure: ended / n})

    ended_figure = "terminated_rate"  # what `eval_outcome` calls the share that ended


class ReachNarrator(Narrator):
    """An episode that reaches its end (`reached_words`), or runs out of time; with three
    `tally_words`, an end that pays nothing or less counts under the second."""

    tally_words: tuple[TallyWord, ...] = (
        TallyWord("reached", "good"), TallyWord("timed out", "even"),
    )
    reached_words = "Reached the goal"  # how reaching the end reads: "Passenger delivered"
    missed_words = ""  # what was not done, after "Out of time after 9 steps"

    def tally_word(self, last: PlayStep) -> str:
        words = self.tally_words
        if not last.terminated:
            return words[-1].label
        return words[0].label if last.episode_return > 0 or len(words) < 3 else words[1].label

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        steps, total = plural(last.steps, "step"), format_reward(last.episode_return)
        if last.terminated:
            return f"{self.reached_words} in {steps}, return {total}"
        return f"Out of time after {steps}{self.missed_words}, return {total}"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        return f"{plural(last.steps, 'step')} taken" if last.steps else ""


class HeatmapLayout(Role):
    """The Q-table as heatmap panels, and the focus cell a person may move."""

    has_focus = False  # the panels follow a focus (GridWorld's target, Taxi's slice)
    focus_help = ""  # what moving the focus does, for the key help

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None,
        marks: BoolArray | NotAvailable | None = None,
    ) -> list[Heatmap]:
        """Panels for `q` (rows: base states); `marks` ([states, actions], from
        `Oracle.optimal_marks`) leaves unmarked the cells whose greedy action is optimal."""
        return []

    def default_focus(self, kwargs: Mapping[str, Any]) -> Any:
        """The focus the heatmaps start with (None when the game has none)."""
        return None

    def focus_at(self, row: int, col: int, kwargs: Mapping[str, Any]) -> Any:
        """The focus that cell (row, col) of the first panel stands for."""
        return None

    def focus_cell(self, focus: Any, kwargs: Mapping[str, Any]) -> tuple[int, int] | None:
        """The first panel's cell of a focus; the inverse of `focus_at`."""
        return None


TIED = "·"  # a heatmap cell whose actions tie


def numbered(count: int) -> tuple[str, ...]:
    """Row or column labels '0' to 'count - 1'."""
    return tuple(str(i) for i in range(count))


def greedy_panel(
    title: str, legend: str, row_labels: tuple[str, ...], col_labels: tuple[str, ...],
    fixed: Callable[[int, int], str | None], q_at: Callable[[int, int], np.ndarray],
    arrow: Callable[[int], str], wrong: Callable[[int, int, int], bool],
    tied: Callable[[int, int], str] = lambda r, c: TIED,
) -> Heatmap:
    """A panel of max Q and labels, cell by cell: the `fixed` label where there is one
    (and no value), else max Q with the `tied` label where every action ties, or else the
    greedy action's `arrow`, marked where that action is `wrong`."""
    rows, cols = len(row_labels), len(col_labels)
    values = np.full((rows, cols), np.nan)
    marked = np.zeros((rows, cols), dtype=bool)
    labels = []
    for r in range(rows):
        line = []
        for c in range(cols):
            label = fixed(r, c)
            if label is None:
                qs = q_at(r, c)
                values[r, c] = float(qs.max())
                action = int(np.argmax(qs))
                if (qs == qs[0]).all():
                    label = tied(r, c)
                else:
                    label = arrow(action)
                    marked[r, c] = wrong(r, c, action)
            line.append(label)
        labels.append(tuple(line))
    return Heatmap(title, row_labels, col_labels, values, tuple(labels), marked, legend)


# --- the game ----------------------------------------------------------------------


class Game:
    """One game: identity and parameters, and its roles (see the module docstring)."""

    name: str = ""  # short alias, e.g. "frozenlake"
    title: str = ""  # for people, e.g. "FrozenLake"
    env_id: str = ""  # the Gymnasium id it plays
    other_ids: tuple[str, ...] = ()  # further ids of the same game
    key: str = ""  # the app's hotkey for it ("" for none)
    description: str = ""  # one line: what the game is
    teaches: str = ""  # one line: what it teaches
    params: tuple[Param, ...] = ()  # the arguments a person may change
    action_names: tuple[str, ...] = ()
    board: str = "text"  # which kind of board draws `states.scene`
    render_mode: str | None = None  # the env's text render mode, if it has one
    episode_noun: str = "episode"  # what people call one episode, e.g. "hand"
    editable: bool = False  # whether the app's map editor edits its maps
    map_tools: tuple[str, ...] = ()  # what the editor paints with (`games.maps.TOOLS` names)
    # `tui-gym bench` measures the game with these arguments (None: it does not), to a
    # target gap of `bench_gap` (None: the bound its oracle states).
    bench_kwargs: dict[str, Any] | None = None
    bench_gap: float | None = None
    demo_wrappers: tuple[str, ...] = ()  # wrapper specs a screenshot of the panel ticks
    # Settings and episodes of the comparison of Q-learning and SARSA a screenshot of the
    # Compare view records (None: the screenshot compares on another game).
    demo_compare: tuple[Mapping[str, Any], int] | None = None
    # Hyperparameters that learn this game well, over each algorithm's own defaults:
    # "*" for every algorithm, then an algorithm's registry name for its own (see the README).
    hyperparameters: ClassVar[Mapping[str, Mapping[str, Any]]] = {}
    # Algorithms (by registry name) whose defaults end short of the game's bound by their
    # nature, not by chance, and why, in a sentence: what the run teaches (see the README).
    lessons: ClassVar[Mapping[str, str]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        cls.params = tuple(replace(param, owner=cls.title) for param in cls.params)

    # The classes of its roles, each made with the game.
    states_type: ClassVar[type[StateSpace]] = StateSpace
    oracle_type: ClassVar[type[Oracle]] = Oracle
    narrator_type: ClassVar[type[Narrator]] = Narrator
    layout_type: ClassVar[type[HeatmapLayout]] = HeatmapLayout

    def __init__(self) -> None:
        self.states: StateSpace = self.states_type(self)
        self.oracle: Oracle = self.oracle_type(self)
        self.narrator: Narrator = self.narrator_type(self)
        self.layout: HeatmapLayout = self.layout_type(self)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.env_id}>"

    # --- ids and arguments ---------------------------------------------------
    @property
    def ids(self) -> tuple[str, ...]:
        return (self.env_id, *self.other_ids)

    def matches(self, env_id: str) -> bool:
        return env_id in self.ids

    def default_kwargs(self) -> dict[str, Any]:
        """The arguments the game starts with."""
        return {p.name: p.default for p in self.params}

    def normalize_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """Check and complete arguments; `ValueError` with a clear message when wrong."""
        params = {p.name: p for p in self.params}
        out = self.default_kwargs()
        for key, value in kwargs.items():
            if key not in params:
                known = ", ".join(params) or "no arguments"
                raise ValueError(f"{self.title} takes {known}, not {shown_value(key)}")
            out[key] = params[key].parse(value)
        self.check_kwargs(out)
        return out

    def check_kwargs(self, kwargs: Mapping[str, Any]) -> None:
        """Check arguments that only make sense together; `ValueError` when they don't."""

    def make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """What `gym.make` takes for these (normalized) arguments."""
        return dict(kwargs)

    def with_map(self, kwargs: Mapping[str, Any], grid_map: Any) -> dict[str, Any]:
        """The arguments that play `grid_map` (a `games.maps.GridMap`), the others kept;
        `ValueError` when this game plays no such map."""
        raise ValueError(f"{self.title} plays on no map; maps are for the grid games")

    def grid_map(self, kwargs: Mapping[str, Any]) -> Any:
        """The map these arguments play (a `games.maps.GridMap`), None for a game
        without maps."""
        return None

    def solution(self, kwargs: Mapping[str, Any]) -> Optimum | NotAvailable:
        """The optimum with action values per base state where there are any (what the
        map editor colours and points arrows with): `oracle.optimum` by default."""
        return self.oracle.optimum(kwargs)

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel | NotAvailable:
        """The exact model the Plan view and `tui-gym plan` sweep, or why there is none."""
        return NotAvailable(f"{self.title} has no exact model to plan on")

    def at_step(self, kwargs: Mapping[str, Any], steps: int) -> dict[str, Any]:
        """The arguments the exact figures take after `steps` steps (counted over episodes):
        these, in a world that never changes; with its phase then, in one that does."""
        return dict(kwargs)

    def make_id(self, env_id: str, kwargs: Mapping[str, Any]) -> str:
        """The id `gym.make` builds for these arguments: `env_id` (the one asked for),
        unless they need another env (an edited map)."""
        return env_id

    def hyperparameter_table(
        self, kwargs: Mapping[str, Any] | None = None
    ) -> Mapping[str, Mapping[str, Any]]:
        """The game's `hyperparameters` for these arguments (a larger map may need others)."""
        return self.hyperparameters

    def default_hyperparameters(
        self, algorithm: str, kwargs: Mapping[str, Any] | None = None, prediction: bool = False
    ) -> dict[str, Any]:
        """The values this game sets for an algorithm (by registry name) over its defaults:
        the "*" entry (a prediction learner's "prediction" entry), then the algorithm's."""
        table = self.hyperparameter_table(kwargs)
        return {**table.get("prediction" if prediction else "*", {}), **table.get(algorithm, {})}

    def episode_limit(self, kwargs: Mapping[str, Any]) -> int | None:
        """The limit `gym.make` puts on the game with these arguments (None: none)."""
        make = self.make_kwargs(kwargs)
        if "max_episode_steps" in make:
            return int(make["max_episode_steps"])
        import gymnasium as gym

        spec = gym.registry.get(self.env_id.rpartition(":")[2])
        return None if spec is None else spec.max_episode_steps

    def action_index(self, action: int | str) -> int:
        """An action given as its number or its name (case-insensitive)."""
        names = self.action_names
        if isinstance(action, bool):
            raise ValueError(f"invalid action {action!r}")
        if isinstance(action, int | np.integer):
            if 0 <= int(action) < len(names):
                return int(action)
        elif isinstance(action, str):
            text = action.strip().lower()
            if text in names:
                return names.index(text)
            # ASCII digits only ('١' and '²' are digits to Python, not to the protocol).
            if text.isascii() and text.isdigit() and int(text) < len(names):
                return int(text)
        listed = ", ".join(f"{i}={n}" for i, n in enumerate(names))
        raise ValueError(f"invalid action {action!r}; valid actions: {listed}")

    # --- the engine --------------------------------------------------------
    def training_model(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> TrainingModel | NotAvailable:
        """The game's model as the wrappers read into `changes` make it, whose states the
        agent's table rows follow, or why there is none."""
        return NotAvailable(f"{self.title} has no exact model")


def ansi_text(env: Any) -> str:
    """The env's text render without terminal colour codes (Gymnasium's text renders use
    them); '' when it has none."""
    import re

    try:
        picture = env.render()
    except UNREADABLE:
        return ""
    return re.sub(r"\x1b\[[0-9;]*m", "", picture) if isinstance(picture, str) else ""
