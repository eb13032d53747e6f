"""The temporal-difference figures (Chapter 6): TD(0) against Monte Carlo on the random walk
(6.2), Sarsa on Windy GridWorld (6.3), Sarsa, Expected Sarsa and Q-learning on CliffWalking
(6.4, 6.6) and Double Q-learning against the maximization bias (6.5)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from tui_gym.core.mdp import FiniteMDP, evaluate, solve
from tui_gym.envs.max_bias import ACTIONS, MAX_B_ACTIONS, A, offered
from tui_gym.games import game_named
from tui_gym.games.planning import PlanModel
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    Series,
    book_figure,
)
from tui_gym.session.book.runs import (
    BANDS,
    FIRST_ACTION,
    LENGTH,
    Played,
    above,
    below,
    book_settings,
    completed,
    counts,
    near,
    per_episode,
    per_time_step,
    play,
    play_prediction,
    swept,
)
from tui_gym.session.experiments.compare import Arm

__all__ = ["FIGURES"]

EPSILON = 0.1  # every control learner of the chapter explores with ε = 0.1 throughout

# --- Figure 6.2 (Example 6.2): TD(0) against constant-α MC on the 5-state random walk ------

TD_ALPHAS = (0.15, 0.1, 0.05)
MC_ALPHAS = (0.01, 0.02, 0.03, 0.04)
START = 0.5  # every estimate starts half-way, as the book's do
WALKERS = (
    *(Arm("td0", {"learning_rate": a, "initial_value": START}, f"TD α={a:g}")
      for a in TD_ALPHAS),
    *(Arm("mc-prediction", {"learning_rate": a, "initial_value": START}, f"MC α={a:g}")
      for a in MC_ALPHAS),
)
LATE = 25  # the last episodes, where the curves have settled


@book_figure(
    "6.2", "random-walk", runs=100, episodes=100, aliases=("example 6.2",),
    title="TD(0) against constant-α MC on the random walk (Example 6.2): RMS error",
    about="Both learn the random policy's values on the 5-state walk; TD(0), bootstrapping "
          "from the next state's estimate, gets closer in fewer episodes than Monte Carlo "
          "at every step size shown. A larger step learns faster at first and settles "
          "higher.")
def fig_6_2(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    played = play_prediction(figure, 5, WALKERS, options, progress)
    late = {p.label: p.values[:, -LATE:].mean(axis=1) for p in played}
    td = [late[x.label] for x in WALKERS[: len(TD_ALPHAS)]]
    mc = [late[x.label] for x in WALKERS[len(TD_ALPHAS):]]
    best_td, best_mc = min(td, key=lambda v: v.mean()), min(mc, key=lambda v: v.mean())
    checks = (
        below(f"TD(0) ends lower than constant-α MC, each at its best α (mean RMS error of "
              f"the last {LATE} episodes)", "TD lower", best_td, best_mc, digits=3),
        above(f"A larger step settles higher: TD(0) with α = {TD_ALPHAS[0]:g} against "
              f"{TD_ALPHAS[-1]:g} (last {LATE} episodes)", "higher", td[0], td[-1], digits=3),
    )
    return FigureResult(
        charts=(Chart("RMS error of V, averaged over the 5 states", "episodes",
                      tuple(per_episode(p) for p in played)),),
        runs=played[0].runs, checks=checks,
        notes=("the random policy's values 1/6 … 5/6, from policy evaluation on the model; "
               f"V starts at {START:g}, undiscounted", BANDS),
    )


# --- Figure 6.3 (Example 6.5): Sarsa on Windy GridWorld -------------------------------------

WINDY = book_settings(1.0, EPSILON, learning_rate=0.5)  # Q starting at 0
STEPS = 8000  # the figure's time steps
FIRST = 20  # episodes compared at the start and at the end


@book_figure(
    "6.3", "windy", runs=20, episodes=200, aliases=("example 6.5",),
    title="Sarsa on Windy GridWorld (Example 6.5): episodes completed against time steps",
    about="The first episode takes thousands of steps; as Sarsa learns, each takes fewer and "
          "the curve steepens towards one episode every 17 or so steps: the 15-step path "
          "plus exploration. With king's moves the path is 7 steps.")
def fig_6_3(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    (rook,) = play(figure, "windy", (Arm("sarsa", WINDY, "Sarsa"),), options, progress,
                   measure=LENGTH)
    (king,) = play(figure, "windy-king", (Arm("sarsa", WINDY, "Sarsa, king's moves"),),
                   options, progress, measure=LENGTH)
    reach = min(STEPS, int(rook.values.sum(axis=1).min()))
    by_then = completed(rook, [reach])[:, 0]
    count = min(FIRST, rook.values.shape[1] // 2)
    checks = (
        _shortest("the shortest path takes 15 steps", 15, "windy"),
        _shortest("with king's moves (Exercise 6.9), 7", 7, "windy-king"),
        Check("exploring with ε = 0.1 on the optimal policy, an episode takes about 17 steps",
              17, round(_epsilon_greedy_length(), 2), abs(_epsilon_greedy_length() - 17) < 0.5),
        near(f"episodes completed by {reach} time steps", 170 * reach / STEPS, by_then,
             digits=0, one_run=True),
        above(f"episodes get shorter: the first {count} against the last {count} (steps)",
              "the slope rises", rook.values[:, :count].mean(axis=1),
              rook.values[:, -count:].mean(axis=1)),
    )
    optimal = int((rook.final == rook.optimum).sum()) if rook.final is not None else 0
    return FigureResult(
        charts=(Chart("episodes completed", "time steps",
                      (per_time_step(rook, until=STEPS), per_time_step(king, until=STEPS))),),
        runs=rook.runs, checks=checks,
        notes=(f"ε = {EPSILON} throughout, α = 0.5, Q starting at 0; the book's figure is one "
               "run, so its count is checked against the spread of one run",
               f"after the last episode the greedy policy takes the shortest path in {optimal} "
               f"of {rook.runs} runs: with α = 0.5 the values stay noisy, and some greedy "
               "policies walk into the wind for ever", BANDS),
    )


def _shortest(claim: str, book: int, world: str) -> Check:
    steps = -solve(_model(world)).value
    return Check(claim, book, round(steps), abs(steps - book) < 1e-9)


def _epsilon_greedy_length() -> float:
    """The expected episode length of ε-greedy on the optimal action values (exact)."""
    model = _model("windy")
    q = solve(model).q
    best = q == q.max(axis=1, keepdims=True)
    policy = (1 - EPSILON) * best / best.sum(axis=1, keepdims=True) + EPSILON / q.shape[1]
    return -float(evaluate(model, policy).value)


def _model(world: str) -> FiniteMDP:
    plan = game_named(world).plan_model({})
    assert isinstance(plan, PlanModel)
    return plan.model


# --- Figure 6.4 (Example 6.6): Sarsa against Q-learning on CliffWalking, online return ------

CLIFF = book_settings(1.0, EPSILON, learning_rate=0.5)
SMOOTHING = 10  # episodes: each run's curve is smoothed over this many, as the book's is
SAFE_PATH = -17.0  # the path along the top of the grid, the farthest from the cliff


@book_figure(
    "6.4", "cliffwalking", runs=20, episodes=500, full_runs=100, aliases=("example 6.6",),
    title="Sarsa against Q-learning on CliffWalking (Example 6.6): online return",
    about="Q-learning learns the optimal path along the cliff's edge but, exploring, falls "
          "off now and then; Sarsa learns the safer path above it and earns more online.")
def fig_6_4(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    sarsa, q = play(figure, "cliffwalking", (Arm("sarsa", CLIFF, "Sarsa"),
                                              Arm("q-learning", CLIFF, "Q-learning")),
                    options, progress)
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
        charts=(Chart(f"online return (each run smoothed over {SMOOTHING} episodes)",
                      "episodes", (per_episode(sarsa, window=SMOOTHING),
                                   per_episode(q, window=SMOOTHING)), skip_start=True),),
        runs=sarsa.runs, checks=checks,
        notes=("ε = 0.1 throughout, α = 0.5, undiscounted; the optimal path is worth "
               f"{q.optimum:g}, the path along the top {SAFE_PATH:g}", BANDS),
    )


# --- Figure 6.5 (Example 6.7): Q-learning against Double Q-learning, % left from A ---------

BIASED = book_settings(1.0, EPSILON, learning_rate=0.1)
LEFT = ACTIONS.index("left")
IN_A = int(offered(MAX_B_ACTIONS)[A].sum())  # the actions A offers: left and right
EARLY = 100  # episodes: the first ones, where the bias shows, and the last ones
# Percentage points: how closely the book's figure is read (its axis is marked every 25
# points; Double Q-learning's curve comes down to just above the 5% line, still coming down
# at episode 300, as a constant α keeps its estimate of left noisy).
READING = 2.5


@book_figure(
    "6.5", "max-bias", runs=1000, episodes=300, full_runs=10_000, aliases=("example 6.7",),
    title="Q-learning against Double Q-learning (Example 6.7): % left actions from A",
    about="Left leads to B, worth -0.1 on average; right ends at 0. Q-learning's max over B's "
          "noisy estimates makes left look good at first, so it goes left far more often "
          "than it should; Double Q-learning is hardly fooled.")
def fig_6_5(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    q, double = play(figure, "max-bias", (Arm("q-learning", BIASED, "Q-learning"),
                                           Arm("double-q", BIASED, "Double Q-learning")),
                     options, progress, measure=FIRST_ACTION)
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
        charts=(Chart("% left actions from A", "episodes",
                      (per_episode(replace(q, values=q_left)),
                       per_episode(replace(double, values=d_left)))),),
        runs=q.runs, checks=checks,
        notes=(f"ε = {EPSILON}, α = 0.1; every action from B ends with a reward drawn from "
               "N(-0.1, 1)",
               f"A offers two actions, so the ε-greedy optimum goes left ε/2 = {optimum:g}% of "
               "the time; the learners explore and take their max over the actions each state "
               "offers", BANDS),
    )


# --- Figure 6.6: interim and asymptotic return against α on CliffWalking -------------------

ALPHAS = tuple(round(0.1 * i, 1) for i in range(1, 11))
KINDS = (("Sarsa", "sarsa"), ("Expected Sarsa", "expected-sarsa"), ("Q-learning", "q-learning"))
INTERIM = 100  # episodes: interim performance is the mean return of a run's first 100
ASYMPTOTIC_RUNS = 8  # the asymptotic runs of the short version (the book's: 10)
FULL_ASYMPTOTIC_RUNS = 10
SETTLED = 0.5  # Sarsa does well in the long run only at a small α: up to this one
LOWEST = -160.0  # the book's axis ends here: points below it are left off the chart
WIDE = 8  # α at which Expected Sarsa must be above both others ("a wide range of α")

PerRun = dict[str, list[np.ndarray]]  # learner -> one number a run, per α


def learners() -> list[Arm]:
    """Each learner of Figure 6.6 at each α, a learner's α together."""
    return [Arm(name, book_settings(1.0, EPSILON, learning_rate=alpha), f"{label} α={alpha:g}")
            for label, name in KINDS for alpha in ALPHAS]


@book_figure(
    "6.6", "cliffwalking", runs=300, episodes=2000, full_runs=50_000, full_episodes=100_000,
    title="Sarsa, Expected Sarsa and Q-learning on CliffWalking (Example 6.6): interim and "
          "asymptotic return against α",
    about="Expected Sarsa does best across α, early and in the long run, and keeps its "
          "return at α = 1; Sarsa does well in the long run only at a small α; Q-learning, "
          "learning the path along the edge while exploring, earns least in the long run.")
def fig_6_6(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    runs, episodes = counts(figure, options)
    asymptotic_runs = FULL_ASYMPTOTIC_RUNS if options.full else ASYMPTOTIC_RUNS
    interim = play(figure, "cliffwalking", learners(), options, progress, runs=runs,
                   episodes=INTERIM)
    long = play(figure, "cliffwalking", learners(), options, progress, runs=asymptotic_runs,
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
        charts=(Chart(f"interim: mean return of the first {INTERIM} episodes, {runs:,} runs",
                      "α", _series(interim)),
                Chart(f"asymptotic: mean return of {episodes:,} episodes, "
                      f"{asymptotic_runs} runs", "α", _series(long))),
        runs=runs, checks=checks,
        notes=(f"ε = {EPSILON} throughout, Q starting at 0, undiscounted; points below "
               f"{LOWEST:g} (the book's axis) are left off the charts", BANDS),
    )


def _per_run(played: Sequence[Played]) -> PerRun:
    """Each learner's runs' mean returns, per α."""
    size = len(ALPHAS)
    return {label: [p.values.mean(axis=1) for p in played[k * size: (k + 1) * size]]
            for k, (label, _) in enumerate(KINDS)}


def _series(played: Sequence[Played]) -> tuple[Series, ...]:
    size = len(ALPHAS)
    return tuple(swept(label, ALPHAS, played[k * size: (k + 1) * size],
                       lambda values: values.mean(axis=1), shown=(LOWEST, np.inf))
                 for k, (label, _) in enumerate(KINDS))


def _highest(phase: str, per_run: PerRun) -> Check:
    """Expected Sarsa above neither other at any α, and above both over a wide range."""
    es = per_run["Expected Sarsa"]
    others = [v for label, v in per_run.items() if label != "Expected Sarsa"]
    first = [all(above("", "", es[i], other[i]).ok for other in others) for i in range(len(ALPHAS))]
    beaten = [a for i, a in enumerate(ALPHAS)
              if any(above("", "", other[i], es[i]).ok for other in others)]
    measured = f"above both at {sum(first)} of {len(ALPHAS)} α" + (
        f"; below one at α = {', '.join(f'{a:g}' for a in beaten)}" if beaten else
        ", below neither at any")
    return Check(f"Expected Sarsa's {phase} return is the highest of the three across α",
                 f"highest at every α (above both at {WIDE} or more)", measured,
                 not beaten and sum(first) >= WIDE)


def _lowest(per_run: PerRun, label: str, where: Sequence[int]) -> Check:
    """`label`'s return below each other learner's at each α of `where`."""
    others = [v for name, v in per_run.items() if name != label]
    lowest = [ALPHAS[i] for i in where
              if all(above("", "", other[i], per_run[label][i]).ok for other in others)]
    span = f"α = {ALPHAS[where[0]]:g} to {ALPHAS[where[-1]]:g}"
    return Check(f"{label}'s asymptotic return is the lowest of the three ({span}, where "
                 "Sarsa does well in the long run)", "lowest",
                 f"lowest at {len(lowest)} of {len(where)} α", len(lowest) == len(where))


FIGURES = (fig_6_2, fig_6_3, fig_6_4, fig_6_5, fig_6_6)
