"""What Figures 8.4 and 8.5 share: Dyna-Q against Dyna-Q+ on a maze whose wall moves."""

from __future__ import annotations

import numpy as np

from tui_gym.core.mdp import solve, with_horizon
from tui_gym.session.book.figure import BookFigure, FigureOptions, Progress
from tui_gym.session.book.runs import Learner, Played, play_steps, world_phases

__all__ = ["KAPPA", "LEARNERS", "PLANNING", "SETTINGS", "episodes_after", "fewest_steps",
           "found_after", "play_maze", "reward_between"]

# The book gives no settings for these figures beyond Example 8.1's (ε = 0.1, γ = 0.95);
# in a deterministic maze α = 1 makes each update take the model's target whole.
PLANNING = 50
KAPPA = 0.001
SETTINGS = {"learning_rate": 1.0, "learning_rate_schedule": "constant", "discount": 0.95,
            "epsilon_start": 0.1, "epsilon_final": 0.1, "planning_steps": PLANNING}
LEARNERS = (Learner("Dyna-Q", "dyna-q", SETTINGS),
            Learner("Dyna-Q+", "dyna-q-plus", {**SETTINGS, "kappa": KAPPA}))
NOTE = (f"ε = 0.1, γ = 0.95, α = 1, {PLANNING} planning steps, κ = {KAPPA:g} (the book gives "
        "no settings for this figure)")


def play_maze(figure: BookFigure, world: str, options: FigureOptions, progress: Progress,
              steps: int, change_at: int) -> list[Played]:
    """Dyna-Q and Dyna-Q+ over the figure's runs, `steps` time steps each."""
    return play_steps(figure, world, LEARNERS, options, progress, steps,
                      game_params={"change_at": change_at})


def reward_between(played: Played, first: int, last: int) -> np.ndarray:
    """Per run, the reward earned from time step `first` + 1 to `last`."""
    before = played.values[:, first - 1] if first > 0 else 0.0
    return played.values[:, last - 1] - before


def _arrivals(row: np.ndarray) -> np.ndarray:
    """The time steps (counted from 1) at which a run's episodes reached the goal."""
    return np.flatnonzero(np.diff(row, prepend=0.0) > 0) + 1


def episodes_after(played: Played, step: int) -> list[np.ndarray]:
    """Per run, the lengths of the episodes begun at or after time step `step` that ended
    within the run."""
    lengths = []
    for row in played.values:
        ends = _arrivals(row)
        begins = np.concatenate(([0], ends))[: len(ends)]
        lengths.append((ends - begins)[begins >= step])
    return lengths


def found_after(played: Played, step: int) -> np.ndarray:
    """Per run, the time steps from `step` until the first episode begun at or after it
    reached the goal (the rest of the run where none did)."""
    found = []
    for row in played.values:
        ends = _arrivals(row)
        begins = np.concatenate(([0], ends))[: len(ends)]
        later = ends[begins >= step]
        found.append(later[0] - step if later.size else len(row) - step)
    return np.asarray(found, dtype=np.float64)


def fewest_steps(world: str, change_at: int) -> tuple[int, ...]:
    """The fewest steps from the start to the goal in each phase of the maze (exact)."""
    fewest = []
    for model in world_phases(world, {"change_at": change_at}).models:
        steps = model.replace(reward=np.full(model.reward.shape, -1.0), reward_std=None)
        fewest.append(round(-solve(with_horizon(steps, None)).value))
    return tuple(fewest)
