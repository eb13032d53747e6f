"""Figure 6.6 (Example 6.6): Sarsa, Expected Sarsa and Q-learning on CliffWalking against α,
the mean return of the first 100 episodes (interim) and of long runs (asymptotic).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
)
from tui_gym.session.book.runs import Learner, Played, above, counts, play, swept

ALPHAS = tuple(round(0.1 * i, 1) for i in range(1, 11))
EPSILON = 0.1
# The book's settings: ε-greedy with ε = 0.1 throughout, constant α, undiscounted.
SETTINGS = {"learning_rate_schedule": "constant", "discount": 1.0, "epsilon_start": EPSILON,
            "epsilon_final": EPSILON}
KINDS = (("Sarsa", "sarsa"), ("Expected Sarsa", "expected-sarsa"), ("Q-learning", "q-learning"))
INTERIM = 100  # episodes: interim performance is the mean return of a run's first 100
ASYMPTOTIC_RUNS = 8  # the asymptotic runs of the short version (the book's: 10)
FULL_ASYMPTOTIC_RUNS = 10
SETTLED = 0.5  # Sarsa does well in the long run only at a small α: up to this one
LOWEST = -160.0  # the book's axis ends here: points below it are left off the chart
WIDE = 8  # α at which Expected Sarsa must be above both others ("a wide range of α")

PerRun = dict[str, list[np.ndarray]]  # learner -> one number a run, per α


def learners() -> list[Learner]:
    """Each learner at each α, a learner's α together."""
    return [Learner(f"{label} α={alpha:g}", name, {**SETTINGS, "learning_rate": alpha})
            for label, name in KINDS for alpha in ALPHAS]


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    runs, episodes = counts(FIGURE, options)
    asymptotic_runs = FULL_ASYMPTOTIC_RUNS if options.full else ASYMPTOTIC_RUNS
    interim = play(FIGURE, "cliffwalking", learners(), options, progress, runs=runs,
                   episodes=INTERIM)
    long = play(FIGURE, "cliffwalking", learners(), options, progress, runs=asymptotic_runs,
                episodes=episodes)
    early, late = _per_run(interim), _per_run(long)
    sarsa = early["Sarsa"]
    best = int(np.argmax([v.mean() for v in sarsa]))
    checks = (
        _highest("interim", early),
        _highest("asymptotic", late),
        _lowest(late, "Q-learning", [i for i, a in enumerate(ALPHAS) if a <= SETTLED]),
        above(f"Sarsa's interim return falls off at high α (α = {ALPHAS[best]:g}, its best, "
              "against α = 1)", "falls off", sarsa[best], sarsa[-1]),
        above("Sarsa's asymptotic return falls off at high α (α = 0.1 against α = 1)",
              "falls off", late["Sarsa"][0], late["Sarsa"][-1]),
        Check("Expected Sarsa keeps its asymptotic return at α = 1 (not below α = 0.1)",
              "no degradation", f"{late['Expected Sarsa'][-1].mean():.1f} vs "
              f"{late['Expected Sarsa'][0].mean():.1f}",
              not above("", "", late["Expected Sarsa"][0], late["Expected Sarsa"][-1]).ok),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=runs,
        charts=(Chart(f"interim: mean return of the first {INTERIM} episodes, {runs:,} runs",
                      "α", _series(interim)),
                Chart(f"asymptotic: mean return of {episodes:,} episodes, "
                      f"{asymptotic_runs} runs", "α", _series(long))),
        checks=checks,
        notes=(f"ε = {EPSILON} throughout, Q starting at 0, undiscounted; points below "
               f"{LOWEST:g} (the book's axis) are left off the charts",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


def _per_run(played: Sequence[Played]) -> PerRun:
    """Each learner's runs' mean returns, per α."""
    size = len(ALPHAS)
    return {label: [p.values.mean(axis=1) for p in played[k * size: (k + 1) * size]]
            for k, (label, _) in enumerate(KINDS)}


def _series(played: Sequence[Played]) -> tuple[Series, ...]:
    size, found = len(ALPHAS), []
    for k, (label, _) in enumerate(KINDS):
        full = swept(label, ALPHAS, played[k * size: (k + 1) * size],
                     lambda values: values.mean(axis=1))
        assert full.lo is not None and full.hi is not None  # a sweep has bands
        keep = full.y >= LOWEST
        found.append(Series(label, full.x[keep], full.y[keep], full.lo[keep], full.hi[keep]))
    return tuple(found)


def _highest(phase: str, per_run: PerRun) -> Check:
    """Expected Sarsa above neither other at any α, and above both over a wide range."""
    es = per_run["Expected Sarsa"]
    others = [v for label, v in per_run.items() if label != "Expected Sarsa"]
    first = [all(above("", "", es[i], other[i]).ok for other in others) for i in range(len(ALPHAS))]
    below = [a for i, a in enumerate(ALPHAS)
             if any(above("", "", other[i], es[i]).ok for other in others)]
    measured = f"above both at {sum(first)} of {len(ALPHAS)} α" + (
        f"; below one at α = {', '.join(f'{a:g}' for a in below)}" if below else
        ", below neither at any")
    return Check(f"Expected Sarsa's {phase} return is the highest of the three across α",
                 f"highest at every α (above both at {WIDE} or more)", measured,
                 not below and sum(first) >= WIDE)


def _lowest(per_run: PerRun, label: str, where: Sequence[int]) -> Check:
    """`label`'s return below each other learner's at each α of `where`."""
    others = [v for name, v in per_run.items() if name != label]
    lowest = [ALPHAS[i] for i in where
              if all(above("", "", other[i], per_run[label][i]).ok for other in others)]
    span = f"α = {ALPHAS[where[0]]:g} to {ALPHAS[where[-1]]:g}"
    return Check(f"{label}'s asymptotic return is the lowest of the three ({span}, where "
                 "Sarsa does well in the long run)", "lowest",
                 f"lowest at {len(lowest)} of {len(where)} α", len(lowest) == len(where))


FIGURE = BookFigure(
    name="6.6",
    title="Sarsa, Expected Sarsa and Q-learning on CliffWalking (Example 6.6): interim and "
          "asymptotic return against α",
    about="Expected Sarsa does best across α, early and in the long run, and keeps its "
          "return at α = 1; Sarsa does well in the long run only at a small α; Q-learning, "
          "learning the path along the edge while exploring, earns least in the long run.",
    world="cliffwalking",
    run=run,
    runs=300,
    episodes=2000,
    full_runs=50_000,
    full_episodes=100_000,
)
