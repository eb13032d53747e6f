"""Human play: one game a person (or a program) plays move by move."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tui_gym.session.recording.recorder import GameRecorder
    from tui_gym.session.session import Session


class PlayError(ValueError):
    """A move that cannot be made now (bad action, no episode running)."""


@dataclass
class Tally:
    """Finished episodes so far: counts, wins/draws/losses and return moments."""

    episodes: int = 0
    wins: int = 0
    draws: int = 0
    losses: int = 0
    total: float = 0.0
    total_sq: float = 0.0

    def add(self, episode_return: float) -> None:
        self.episodes += 1
        self.total += episode_return
        self.total_sq += episode_return * episode_return
        if episode_return > 0:
            self.wins += 1
        elif episode_return < 0:
            self.losses += 1
        else:
            self.draws += 1

    @property
    def mean(self) -> float:
        return self.total / self.episodes if self.episodes else 0.0

    def half_width(self, z: float = 1.96) -> float | None:
        """Half the normal-approximation interval of the mean (None below 2 episodes)."""
        n = self.episodes
        if n < 2:
            return None
        variance = max(0.0, (self.total_sq - n * self.mean * self.mean) / (n - 1))
        return z * math.sqrt(variance / n)

    def confidence_interval(self, z: float = 1.96, min_episodes: int = 2) -> tuple[float, float]:
        """Normal-approximation interval of the mean (NaN below `min_episodes`, or 2)."""
        half = self.half_width(z)
        if half is None or self.episodes < min_episodes:
            return (float("nan"), float("nan"))
        return (self.mean - half, self.mean + half)


@dataclass
class Scorecard:
    """One player's record beside the optimum, in constant memory: finished episodes, moves
    where the optimum had a say (`decisions`) and agreed with it, and running sums of
    per-episode figures (`Narrator.episode_figures`) with their counts."""

    tally: Tally = field(default_factory=Tally)
    decisions: int = 0
    agreed: int = 0
    figures: dict[str, tuple[float, int]] = field(default_factory=dict)  # name -> (sum, count)

    def judge_move(self, optimal: tuple[int, ...], action: int | None) -> bool | None:
        """Count a move against the optimal actions before it; None when there was no decision."""
        if not optimal or action is None:
            return None
        agreed = int(action) in optimal
        self.decisions += 1
        self.agreed += agreed
        return agreed

    def add_figures(self, figures: Mapping[str, float]) -> None:
        """Add one finished episode's figures to the running sums."""
        for name, value in figures.items():
            total, count = self.figures.get(name, (0.0, 0))
            self.figures[name] = (total + float(value), count + 1)

    def figure_mean(self, name: str) -> float | None:
        """The mean of a per-episode figure (None before it was ever measured)."""
        total, count = self.figures.get(name, (0.0, 0))
        return total / count if count else None

    def figure_count(self, name: str) -> int:
        """How many episodes a figure was measured on."""
        return self.figures.get(name, (0.0, 0))[1]

    @property
    def agreement(self) -> float | None:
        """The share of decisions that matched the optimum (None before the first)."""
        return self.agreed / self.decisions if self.decisions else None


@dataclass(frozen=True)
class PlayStep:
    """The state after a reset or a move."""

    observation: Any
    reward: float
    terminated: bool
    truncated: bool
    info: dict[str, Any]
    episode_return: float
    steps: int
    action: int | None = None

    @property
    def done(self) -> bool:
        return self.terminated or self.truncated


@dataclass
class HumanGame:
    """A game played move by move on its own env."""

    session: Session
    seed: int | None = None
    tally: Tally = field(default_factory=Tally)

    def __post_init__(self) -> None:
        self.game = self.session.game
        self.env = self.session.make_env(render_mode=self.game.render_mode)
        self.last: PlayStep | None = None
        self.first_info: dict[str, Any] = {}
        self._seeded = False
        self._before: dict[str, Any] | None = None  # the scene before the last move
        self.recorder: GameRecorder | None = None  # told of every reset and move when set

    def close(self) -> None:
        self.env.close()

    @property
    def done(self) -> bool:
        return self.last is None or self.last.done

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> PlayStep:
        """Start a new episode (the first one uses the game's seed); `options` go to the env."""
        if seed is None and not self._seeded:
            seed = self.seed
        self._seeded = True
        obs, info = self.env.reset(seed=seed, options=options)
        self._before = None
        self.first_info = dict(info)
        self.last = PlayStep(obs, 0.0, False, False, dict(info), 0.0, 0)
        if self.recorder is not None:
            self.recorder.game_reset(self, seed)
        return self.last

    def step(self, action: int | str) -> PlayStep:
        """Make a move; PlayError when the action is invalid or no episode is running."""
        if self.last is None:
            raise PlayError("no episode running: reset first")
        if self.last.done:
            raise PlayError("the episode is over: reset to play again")
        try:
            index = self.game.action_index(action)
        except ValueError as exc:
            raise PlayError(str(exc)) from None
        before = self.game.states.scene(self.env)
        obs, reward, terminated, truncated, info = self.env.step(index)
        self._before = before
        total = self.last.episode_return + float(reward)
        self.last = PlayStep(obs, float(reward), bool(terminated), bool(truncated), dict(info),
                             total, self.last.steps + 1, index)
        if self.last.done:
            self.tally.add(total)
        if self.recorder is not None:
            self.recorder.game_step(self)
        return self.last

    def scene(self) -> dict[str, Any]:
        """What the board draws (see `StateSpace.scene`), the last move included."""
        return self.game.states.scene(self.env, self._before)

    def text(self) -> str:
        """A text picture of the state (hidden cards stay hidden until the end)."""
        return self.game.states.text(self.env, reveal=self.done, before=self._before)
