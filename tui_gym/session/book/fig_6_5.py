"""Figure 6.5 (Example 6.7): Q-learning against Double Q-learning on the maximization-bias MDP,
% of episodes that go left from A."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tui_gym.envs.max_bias import ACTIONS, MAX_B_ACTIONS, A, offered
from tui_gym.session.book.figure import BookFigure, Chart, FigureOptions, FigureResult, Progress
from tui_gym.session.book.runs import FIRST_ACTION, Learner, above, below, near, per_episode, play

# The book's settings: ε = 0.1, α = 0.1, undiscounted.
EPSILON = 0.1
SETTINGS = {"learning_rate": 0.1, "learning_rate_schedule": "constant", "discount": 1.0,
            "epsilon_start": EPSILON, "epsilon_final": EPSILON}
LEARNERS = (Learner("Q-learning", "q-learning", SETTINGS),
            Learner("Double Q-learning", "double-q", SETTINGS))
LEFT = ACTIONS.index("left")
IN_A = int(offered(MAX_B_ACTIONS)[A].sum())  # the actions A offers: left and right
EARLY = 100  # episodes: the first ones, where the bias shows, and the last ones
# Percentage points: how closely the book's figure is read (its axis is marked every 25
# points; Double Q-learning's curve comes down to just above the 5% line, still coming down
# at episode 300, as a constant α keeps its estimate of left noisy).
READING = 2.5


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    q, double = play(FIGURE, "max-bias", LEARNERS, options, progress, measure=FIRST_ACTION)
    q_left, d_left = 100.0 * (q.values == LEFT), 100.0 * (double.values == LEFT)
    early = min(EARLY, q_left.shape[1])
    # The learners take only the actions A offers (left and right), so the ε-greedy
    # optimum goes left ε/2 of the time, as in the book.
    optimum = 100.0 * EPSILON / IN_A
    floor = np.full(q.runs, optimum)
    checks = (
        above(f"Q-learning goes left far more often than the optimum ({optimum:.2f}%) at first "
              f"(episodes 1 to {early})", "up to about 70%", q_left[:, :early].mean(axis=1),
              floor, unit="%"),
        below(f"Double Q-learning goes left less than Q-learning (episodes 1 to {early})",
              "far less", d_left[:, :early].mean(axis=1), q_left[:, :early].mean(axis=1),
              unit="%"),
        near(f"Double Q-learning comes down near the ε-greedy optimum (the last {early} "
             "episodes)",
             round(optimum, 2), d_left[:, -early:].mean(axis=1), slack=READING, digits=2,
             unit="%"),
        above(f"Q-learning is still biased at the end (the last {early} episodes)",
              "above Double Q-learning", q_left[:, -early:].mean(axis=1),
              d_left[:, -early:].mean(axis=1), unit="%"),
        above(f"Q-learning always goes left more often than the {optimum:g}% ε-greedy "
              f"enforces (the last {early} episodes)", "significantly more",
              q_left[:, -early:].mean(axis=1), floor, unit="%"),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=q.runs,
        charts=(Chart("% left actions from A", "episodes",
                      (per_episode(replace(q, values=q_left)),
                       per_episode(replace(double, values=d_left)))),),
        checks=checks,
        notes=(f"ε = {EPSILON}, α = 0.1; every action from B ends with a reward drawn from "
               "N(-0.1, 1)",
               f"A offers two actions, so the ε-greedy optimum goes left ε/2 = {optimum:g}% of "
               "the time; the learners explore and take their max over the actions each state "
               "offers",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="6.5",
    title="Q-learning against Double Q-learning (Example 6.7): % left actions from A",
    about="Left leads to B, worth -0.1 on average; right ends at 0. Q-learning's max over B's "
          "noisy estimates makes left look good at first, so it goes left far more often "
          "than it should; Double Q-learning is hardly fooled.",
    world="max-bias",
    run=run,
    runs=1000,
    episodes=300,
    full_runs=10_000,
    aliases=("example 6.7",),
)
