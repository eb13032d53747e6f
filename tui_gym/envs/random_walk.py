"""Sutton & Barto's random walk: `RandomWalkEnv` (Example 6.2, Figure 7.2)."""

from __future__ import annotations

from tui_gym.envs.dp_grid import Grid, GridEnv

__all__ = ["LEFT_END_PAYS", "RandomWalkEnv", "walk_grid"]

# The walks of the book: states -> what stepping off the left end pays (the right end pays +1).
LEFT_END_PAYS = {5: 0.0, 19: -1.0}


def walk_grid(states: int) -> Grid:
    """The walk with `states` states (5 or 19) between its two ends, as a one-row grid."""
    if states not in LEFT_END_PAYS:
        raise ValueError(f"the random walk has 5 states (Example 6.2) or 19 (Figure 7.2), "
                         f"not {states!r}")
    ends = ((0, 0), (0, states + 1))
    names = "ABCDE" if states == 5 else [str(i) for i in range(1, states + 1)]
    return Grid(1, states + 2, moves=("left", "right"), terminals=ends,
                pays={ends[0]: LEFT_END_PAYS[states], ends[1]: 1.0}, start=(0, states // 2 + 1),
                letters={(0, i + 1): name for i, name in enumerate(names)},
                tiles={ends[0]: "H"})


class RandomWalkEnv(GridEnv):
    """Sutton & Barto's random walk: a row of states between two ends.

    ## Action Space
    left (0), right (1).

    ## Observation Space
    The position, 0 to `states + 1`: 0 and `states + 1` are the two ends, the
    states between them are A to E (5 states) or 1 to 19 (19 states).

    ## Rewards
    Stepping off the right end pays +1; off the left end 0 with 5 states
    (Example 6.2) and -1 with 19 (Figure 7.2); every other step 0.

    ## Starting State
    The middle state (C of A to E; 10 of 1 to 19).

    ## Episode End
    Terminated at either end.

    ## Arguments
    `states`: 5 or 19; `render_mode`: "ansi" draws the row as text.
    """

    def __init__(self, states: int = 5, render_mode: str | None = None) -> None:
        super().__init__(walk_grid(states), render_mode)
        self.states = states
