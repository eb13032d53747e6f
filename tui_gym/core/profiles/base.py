"""What a game profile is: everything that differs per game, in one place.

Front ends never branch on a game's name; they ask the profile: action names
and keys, how a state reads as text, which base states the heatmaps and the
exact reference look at, and how a finished episode is scored.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.agent import Hyperparameters
from tui_gym.core.heatmap import Heatmap
from tui_gym.core.wrappers.params import Param

if TYPE_CHECKING:
    from tui_gym.core.play import PlayStep


@dataclass(frozen=True)
class ReferenceMetrics:
    """How the agent's greedy policy compares with the exact optimum."""

    figures: dict[str, float]  # e.g. exact_value / optimal_value / gap, or optimal_pair_fraction
    summary: str  # one line for people


@dataclass(frozen=True)
class Advice:
    """What the exact optimum would do in the env's current state."""

    optimal: tuple[int, ...]  # every optimal action (empty when there is no decision)
    values: dict[int, float] | None = None  # exact expected return per action, when known
    note: str = ""  # one line for people


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
            if text.isdigit() and int(text) < len(self.action_names):
                return int(text)
        names = ", ".join(f"{i}={n}" for i, n in enumerate(self.action_names))
        raise ValueError(f"invalid action {action!r}; valid actions: {names}")

    @abstractmethod
    def base_observations(self, env_kwargs: Mapping[str, Any]) -> list[Any]:
        """Every state of the bare env that heatmaps and the exact reference look at."""

    @abstractmethod
    def reference(self, q: np.ndarray, env_kwargs: Mapping[str, Any]) -> ReferenceMetrics:
        """Exact comparison of the greedy policy of `q` (rows: base states) with the optimum."""

    @abstractmethod
    def heatmaps(
        self, q: np.ndarray, env_kwargs: Mapping[str, Any], focus: Any = None
    ) -> list[Heatmap]:
        """Heatmap panels for `q` (rows = base_observations); `focus` picks e.g. a target."""

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
        """The optimal action(s) in the env's current (bare) state."""

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


def greedy_policy(q: np.ndarray) -> np.ndarray:
    """Greedy action per row; ties go to the lowest action (deterministic, for exact scoring)."""
    return np.argmax(q, axis=1).astype(np.int64)
