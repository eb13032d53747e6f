"""Figure 6.4 (Example 6.6): Sarsa against Q-learning on CliffWalking, online return per episode."""

from __future__ import annotations

from tui_gym.session.book.figure import BookFigure, Chart, FigureOptions, FigureResult, Progress
from tui_gym.session.book.runs import Learner, above, near, per_episode, play

# The book's settings: ε-greedy with ε = 0.1 throughout, α = 0.5, undiscounted.
SETTINGS = {"learning_rate": 0.5, "learning_rate_schedule": "constant", "discount": 1.0,
            "epsilon_start": 0.1, "epsilon_final": 0.1}
LEARNERS = (Learner("Sarsa", "sarsa", SETTINGS), Learner("Q-learning", "q-learning", SETTINGS))
SMOOTHING = 10  # episodes: each run's curve is smoothed over this many, as the book's is
SAFE_PATH = -17.0  # the path along the top of the grid, the farthest from the cliff


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    sarsa, q = play(FIGURE, "cliffwalking", LEARNERS, options, progress)
    half = sarsa.values.shape[1] // 2  # the later half of the episodes: both have settled
    sarsa_online, q_online = sarsa.values[:, half:].mean(axis=1), q.values[:, half:].mean(axis=1)
    assert sarsa.final is not None and q.final is not None and q.optimum is not None
    checks = (
        above("Sarsa's online return is higher than Q-learning's (later half of the episodes)",
              "about -25 vs -50", sarsa_online, q_online),
        near("Q-learning's greedy policy is the optimal path along the cliff", q.optimum, q.final),
        near("Sarsa's greedy policy keeps off the cliff's edge: % of runs on the optimal path",
             0.0, 100.0 * (sarsa.final == q.optimum), unit="%"),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=sarsa.runs,
        charts=(Chart(f"online return (each run smoothed over {SMOOTHING} episodes)",
                      "episodes", (per_episode(sarsa, window=SMOOTHING),
                                   per_episode(q, window=SMOOTHING)), skip_start=True),),
        checks=checks,
        notes=("ε = 0.1 throughout, α = 0.5, undiscounted; the optimal path is worth "
               f"{q.optimum:g}, the path along the top {SAFE_PATH:g}",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="6.4",
    title="Sarsa against Q-learning on CliffWalking (Example 6.6): online return",
    about="Q-learning learns the optimal path along the cliff's edge but, exploring, falls "
          "off now and then; Sarsa learns the safer path above it and earns more online.",
    world="cliffwalking",
    run=run,
    runs=20,
    episodes=500,
    full_runs=100,
    aliases=("example 6.6",),
)
