"""The planning figures (Chapter 8): Dyna-Q's planning steps on the Dyna maze (8.2), Dyna-Q
against Dyna-Q+ on mazes whose wall moves (8.4, 8.5), and prioritized sweeping against Dyna-Q
on ever finer Dyna mazes (Example 8.4)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tui_gym.algorithms import algorithm
from tui_gym.core.engine import loop
from tui_gym.core.mdp import FiniteMDP, solve, with_horizon
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
    book_figure,
)
from tui_gym.session.book.runs import (
    BANDS,
    LENGTH,
    Played,
    above,
    below,
    book_settings,
    counts,
    margin,
    near,
    per_episode,
    play,
    play_steps,
    swept,
    world_phases,
)
from tui_gym.session.experiments.compare import Arm, Setup, prepare

__all__ = ["FIGURES", "episodes_after", "found_after", "reward_between"]

# --- Figure 8.2: Dyna-Q with 0, 5 and 50 planning steps on the Dyna maze ------------------

PLANNING_STEPS = (0, 5, 50)
DYNA_SETTINGS = book_settings(0.95, learning_rate=0.1)  # Q and the model starting empty
SETTLED = {0: 25, 5: 5, 50: 3}  # the book: the episodes each takes to reach its final level
READING = 10  # steps: how closely a curve is read off the figure's 800-step axis
LAST = 10  # episodes that make a run's final level
EARLY = (2, 10)  # the episodes compared at the start (the book's axis begins at 2)


@book_figure(
    "8.2", "dyna-maze", runs=30, episodes=50, aliases=("example 8.1",),
    title="Dyna-Q on the Dyna maze (Figure 8.2): steps per episode",
    about="The first episode is a long random walk for every agent; after it, an agent that "
          "plans 50 updates a step has a path back nearly to the start by the second episode, "
          "one without planning needs about 25 episodes.")
def fig_8_2(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    played = play(figure, "dyna-maze", [
        Arm("dyna-q", {**DYNA_SETTINGS, "planning_steps": n}, f"{n} planning steps")
        for n in PLANNING_STEPS], options, progress, measure=LENGTH)
    episodes = played[0].values.shape[1]
    first, last = EARLY[0] - 1, min(EARLY[1], episodes)
    early = [p.values[:, first:last].mean(axis=1) for p in played]
    checks = [
        above(f"more planning, fewer steps: {a.label} against {b.label} (episodes "
              f"{EARLY[0]} to {last})", "fewer", x, y)
        for a, b, x, y in zip(played, played[1:], early, early[1:], strict=False)
    ]
    checks += [_settled(p, SETTLED[n]) for n, p in zip(PLANNING_STEPS, played, strict=True)
               if SETTLED[n] + LAST <= episodes]
    return FigureResult(
        charts=(Chart("steps per episode", "episodes",
                      tuple(per_episode(p) for p in played), skip_start=True),),
        runs=played[0].runs, checks=tuple(checks),
        notes=("ε = 0.1, α = 0.1, γ = 0.95; the shortest path takes 14 steps, and exploring "
               "with ε = 0.1 lengthens it",
               f"a run's final level: its mean over the last {LAST} episodes; curves are read "
               f"off the book's figure to ±{READING} steps", BANDS),
    )


def _settled(played: Played, episode: int) -> Check:
    """The episode no longer than the run's final level, beyond the reading and the margin."""
    at = played.values[:, episode - 1]
    final = played.values[:, -LAST:].mean(axis=1)
    excess = at - final
    return Check(f"{played.label}: at its final level by episode {episode}",
                 f"about {episode} episodes",
                 f"{at.mean():.1f} steps at episode {episode}, {final.mean():.1f} at the end",
                 float(np.mean(excess)) <= READING + margin(excess))


# --- Figures 8.4 and 8.5: Dyna-Q against Dyna-Q+ on a maze whose wall moves ----------------

# The book gives no settings for these figures beyond Example 8.1's (ε = 0.1, γ = 0.95);
# in a deterministic maze α = 1 makes each update take the model's target whole.
PLANNING = 50
KAPPA = 0.001
MAZE_SETTINGS = book_settings(0.95, learning_rate=1.0, planning_steps=PLANNING)
MAZE_LEARNERS = (Arm("dyna-q", MAZE_SETTINGS, "Dyna-Q"),
                 Arm("dyna-q-plus", {**MAZE_SETTINGS, "kappa": KAPPA}, "Dyna-Q+"))
MAZE_NOTE = (f"ε = 0.1, γ = 0.95, α = 1, {PLANNING} planning steps, κ = {KAPPA:g} (the book "
             "gives no settings for this figure)")
BLOCKING = (3000, 1000)  # Figure 8.4's time steps, and those after which the wall moves
SHORTCUT = (6000, 3000)  # Figure 8.5's, and those after which the shortcut opens
GLANCE = 100  # steps on each side of the blocking change that show the curves go flat
BLOCKED_LATE = 500  # the last steps of Figure 8.4, where the curves have risen again
SHORTCUT_LATE = 1500  # the last steps of Figure 8.5: each agent's way after the change


def reward_between(played: Played, first: int, last: int) -> np.ndarray:
    """Per run, the reward earned from time step `first` + 1 to `last`."""
    before = played.values[:, first - 1] if first > 0 else 0.0
    return played.values[:, last - 1] - before


def _episodes(row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The time steps (from 1) at which a run's episodes that reached the goal began and ended."""
    ends = np.flatnonzero(np.diff(row, prepend=0.0) > 0) + 1
    return np.concatenate(([0], ends))[: len(ends)], ends


def episodes_after(played: Played, step: int) -> list[np.ndarray]:
    """Per run, the lengths of the finished episodes begun at or after time step `step`."""
    return [(ends - begins)[begins >= step]
            for begins, ends in map(_episodes, played.values)]


def found_after(played: Played, step: int) -> np.ndarray:
    """Per run, the time steps from `step` until an episode begun then reached the goal."""
    found = []
    for row in played.values:
        begins, ends = _episodes(row)
        later = ends[begins >= step]
        found.append(later[0] - step if later.size else len(row) - step)
    return np.asarray(found, dtype=np.float64)


def _steps_cost(model: FiniteMDP) -> FiniteMDP:
    """The maze's model with every step paying -1: its optimum counts the fewest steps."""
    return model.replace(reward=np.full(model.reward.shape, -1.0), reward_std=None)


def _changing_maze(figure: BookFigure, world: str, timing: tuple[int, int],
                   options: FigureOptions, progress: Progress,
                   ) -> tuple[Played, Played, tuple[int, ...]]:
    """Dyna-Q's and Dyna-Q+'s runs on `world` (`timing`: steps, and the change's), and the
    fewest steps from the start to the goal before and after the change (exact)."""
    steps, change = timing
    dyna, plus = play_steps(figure, world, MAZE_LEARNERS, options, progress, steps,
                            game_params={"change_at": change})
    fewest = tuple(round(-solve(with_horizon(_steps_cost(model), None)).value)
                   for model in world_phases(world, {"change_at": change}).models)
    return dyna, plus, fewest


def _maze_result(figure: BookFigure, dyna: Played, plus: Played, checks: tuple[Check, ...],
                 *notes: str) -> FigureResult:
    """A changing maze's figure: both cumulative rewards; Dyna-Q+ ends above Dyna-Q."""
    steps = dyna.values.shape[1]
    last = above(f"Dyna-Q+'s cumulative reward after {steps} steps is above Dyna-Q's",
                 "above", plus.values[:, -1], dyna.values[:, -1])
    return FigureResult(
        charts=(Chart("cumulative reward", "time steps",
                      tuple(per_episode(p, points=300) for p in (dyna, plus))),),
        runs=dyna.runs, checks=(*checks, last), notes=(MAZE_NOTE, *notes, BANDS),
    )


@book_figure(
    "8.4", "blocking-maze", runs=30, aliases=("example 8.2",),
    title="Dyna-Q against Dyna-Q+ on the blocking maze (Figure 8.4): cumulative reward",
    about="After 1000 steps the short way round the wall closes and a longer one opens at "
          "its other end. Both agents' curves go flat while they search behind the wall; "
          "Dyna-Q+, whose planning rewards trying what it has not tried for long, finds "
          "the new way sooner and ends ahead.")
def fig_8_4(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    dyna, plus, (before, after) = _changing_maze(figure, "blocking-maze", BLOCKING, options,
                                                 progress)
    steps, change = BLOCKING
    flat = [above(f"{p.label}'s curve goes flat at the change: reward in the {GLANCE} steps "
                  f"before it against the {GLANCE} after", "flat after the change",
                  reward_between(p, change - GLANCE, change),
                  reward_between(p, change, change + GLANCE)) for p in (dyna, plus)]
    rises = [above(f"{p.label} finds the new way after a while: reward per {GLANCE} steps "
                   f"over the last {BLOCKED_LATE} against the {GLANCE} after the change",
                   "the curve rises again",
                   reward_between(p, steps - BLOCKED_LATE, steps) * GLANCE / BLOCKED_LATE,
                   reward_between(p, change, change + GLANCE)) for p in (dyna, plus)]
    found_dyna, found_plus = found_after(dyna, change), found_after(plus, change)
    checks = (
        Check("the short way round the wall's right end takes 10 steps; after the change, "
              "the way round its left end 16", "10, then 16", f"{before}, then {after}",
              (before, after) == (10, 16)),
        *flat,
        *rises,
        above("Dyna-Q+ finds the new way sooner: time steps from the change until an episode "
              "begun after it reaches the goal (Dyna-Q against Dyna-Q+)", "sooner",
              found_dyna, found_plus, digits=0),
    )
    stuck = int((found_dyna >= steps - change).sum())
    return _maze_result(
        figure, dyna, plus, checks,
        f"the wall moves after {change} steps; the maze pays +1 at the goal only, so the "
        "cumulative reward counts the episodes that reached it",
        f"Dyna-Q had not found the new way by step {steps} in {stuck} of {dyna.runs} runs "
        f"(counted as {steps - change} steps); Dyna-Q+ took "
        f"{float(np.median(found_plus)):.0f} steps (median)")


@book_figure(
    "8.5", "shortcut-maze", runs=30, aliases=("example 8.3",),
    title="Dyna-Q against Dyna-Q+ on the shortcut maze (Figure 8.5): cumulative reward",
    about="After 3000 steps a shorter way opens round the wall's right end, the long way "
          "staying open. Dyna-Q's model says the long way works, so it never tries the "
          "shortcut; Dyna-Q+'s bonus for what it has not tried for long sends it there, and "
          "its curve climbs faster.")
def fig_8_5(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    dyna, plus, (long_way, shortcut) = _changing_maze(figure, "shortcut-maze", SHORTCUT,
                                                      options, progress)
    steps, change = SHORTCUT
    late = steps - SHORTCUT_LATE
    # An episode shorter than the long way's fewest steps went through the shortcut.
    through = [[100.0 * (lengths < long_way).mean() if lengths.size else 0.0
                for lengths in episodes_after(p, late)] for p in (dyna, plus)]
    checks = (
        Check("the long way round the wall's left end takes 16 steps; the shortcut, 10",
              "16, then 10", f"{long_way}, then {shortcut}", (long_way, shortcut) == (16, 10)),
        near(f"Dyna-Q never finds the shortcut: % of its episodes in the last {SHORTCUT_LATE} "
             f"steps shorter than the long way's {long_way}", 0.0, through[0], unit="%"),
        above(f"Dyna-Q+ finds it: % of its episodes in the last {SHORTCUT_LATE} steps through "
              "the shortcut, against Dyna-Q's", "Dyna-Q+ takes it", through[1], through[0],
              unit="%"),
        above(f"after the change Dyna-Q+'s curve is steeper: reward over the last "
              f"{SHORTCUT_LATE} steps", "steeper", reward_between(plus, late, steps),
              reward_between(dyna, late, steps)),
    )
    return _maze_result(
        figure, dyna, plus, checks,
        f"the shortcut opens after {change} steps; the maze pays +1 at the goal only, so the "
        "cumulative reward counts the episodes that reached it")


# --- Example 8.4: prioritized sweeping against Dyna-Q, updates until optimal ---------------

# The book: "both systems made at most n = 5 updates per environmental interaction"; the
# rest as in Example 8.1 (ε = 0.1, γ = 0.95), with α = 1 (a deterministic maze: each update
# takes the model's target whole) and θ = 0.0001.
SWEEP_PLANNING = 5
SWEEP_SETTINGS = {**MAZE_SETTINGS, "planning_steps": SWEEP_PLANNING}
SWEEPERS = (Arm("dyna-q", SWEEP_SETTINGS, "Dyna-Q"),
            Arm("prioritized-sweeping", {**SWEEP_SETTINGS, "theta": 0.0001},
                "Prioritized sweeping"))
SCALES = (1, 2, 4)  # each cell of the Dyna maze made scale x scale cells: 47 to 752 states
FULL_SCALES = (1, 2, 4, 8)  # to 3008 states, the book's axis doubling twice a step
STEPS_PER_STATE = 10_000  # real steps a run may take to become optimal, per state
FACTOR = 5  # the book: prioritized sweeping finds optimal solutions "often by a factor of
# 5 to 10" faster


@book_figure(
    "example 8.4", "dyna-maze", runs=10, aliases=("e8.4", "example-8.4"),
    title="Prioritized sweeping against Dyna-Q on finer Dyna mazes (Example 8.4): updates "
          "until optimal",
    about="The Dyna maze with each cell made 2 x 2 and 4 x 4 cells: the same structure, "
          "more states. Dyna-Q plans from pairs drawn at random, most of whose updates "
          "change nothing; prioritized sweeping plans where values change, backwards from "
          "the goal, and its greedy policy is optimal after many times fewer updates.")
def example_8_4(figure: BookFigure, options: FigureOptions, progress: Progress) -> FigureResult:
    runs, _ = counts(figure, options)
    scales = FULL_SCALES if options.full else SCALES
    updates = np.zeros((len(SWEEPERS), len(scales), runs))
    sizes: list[int] = []
    unfinished = [0] * len(SWEEPERS)
    total = len(SWEEPERS) * len(scales) * runs
    for j, scale in enumerate(scales):
        model, good, hps, cells = _maze(scale, runs, options.seed)
        sizes.append(cells)
        arrays = loop.ModelArrays.of(model)
        for i, (learner, hp) in enumerate(zip(SWEEPERS, hps, strict=True)):
            for r in range(runs):
                options.check_stop(figure.name)
                done = (j * len(SWEEPERS) + i) * runs + r
                progress(done, total, f"{sizes[-1]} states: {learner.label}, run {r + 1}")
                cls = algorithm(learner.algorithm)
                agent = cls(model.n_actions, cls.settings(hp), n_states=model.n_states,
                            seed=options.seed + r)
                updates[i, j, r], late = _updates_until_optimal(agent, arrays, model, good,
                                                                STEPS_PER_STATE * cells)
                unfinished[i] += late
    progress(total, total, "done")
    series = tuple(swept(learner.label, sizes,
                         [Played(learner.label, updates[i, j][:, np.newaxis], None, None)
                          for j in range(len(scales))], lambda values: np.log10(values[:, 0]))
                   for i, learner in enumerate(SWEEPERS))
    dyna, sweeping = np.log10(updates[0]), np.log10(updates[1])
    gap = dyna - sweeping  # per scale and run: log10 of how many times fewer
    checks = [below(f"{size} states: prioritized sweeping needs fewer updates (log10 of "
                    "its own against Dyna-Q's)", "fewer", sweeping[j], dyna[j], digits=2)
              for j, size in enumerate(sizes)]
    checks += [Check(f"{size} states: a decisive advantage, at least {FACTOR} times fewer "
                     "updates (log10 of the factor per run)", f"often {FACTOR} to 10 times",
                     f"{10 ** gap[j].mean():.0f} times (log10 {gap[j].mean():.2f} ± "
                     f"{margin(gap[j]):.2f})", gap[j].mean() - margin(gap[j]) > np.log10(FACTOR))
               for j, size in enumerate(sizes)]
    return FigureResult(
        charts=(Chart("log10 updates until the greedy policy is optimal", "states", series),),
        runs=runs, checks=tuple(checks),
        notes=(f"ε = 0.1, γ = 0.95, α = 1, at most {SWEEP_PLANNING} updates a step (Dyna-Q: "
               f"its own and {SWEEP_PLANNING} planned; prioritized sweeping: what it takes "
               "from its queue, θ = 0.0001)",
               "optimal: from the start, every greedy move (ties all counted) is on a "
               "shortest way to the goal, checked after each episode against the exact "
               "optimum",
               "log10 of Dyna-Q's updates over prioritized sweeping's, by size: "
               + ", ".join(f"{size} states {g:.2f}" for size, g in zip(sizes, gap.mean(axis=1),
                                                                     strict=True)),
               f"runs not optimal within {STEPS_PER_STATE:,} steps a state (counted as they "
               f"stood): Dyna-Q {unfinished[0]}, prioritized sweeping {unfinished[1]}", BANDS),
    )


def _maze(scale: int, runs: int,
          seed: int) -> tuple[FiniteMDP, np.ndarray, list[dict[str, Any]], int]:
    """The Dyna maze made `scale` times finer, its optimal moves (`good[state, action]`),
    each learner's settings, and its open cells (the states the book counts)."""
    prepared = prepare(Setup("dyna-maze", runs, 1, {"scale": scale}, (), seed), list(SWEEPERS))
    model = world_phases("dyna-maze", prepared.env_kwargs).models[0]
    q = solve(with_horizon(_steps_cost(model), None)).q
    good = np.isclose(q, q.max(axis=1, keepdims=True))
    good[(model.next_state[:, :, 0] == np.arange(model.n_states)[:, np.newaxis])
         & ~model.terminal[:, :, 0]] = False  # a move that stays put is never on a way
    reached = model.initial > 0  # the open cells: those a walk from the start reaches
    while True:
        more = reached.copy()
        more[model.next_state[reached].ravel()] = True
        if (more == reached).all():
            return model, good, prepared.hyperparameters, int(reached.sum())
        reached = more


def _updates_until_optimal(agent: Any, arrays: loop.ModelArrays, model: FiniteMDP,
                           good: np.ndarray, most: int) -> tuple[float, bool]:
    """The Q updates `agent` makes until its greedy policy is optimal from the start (looked
    at after each episode), and whether it was still not after `most` steps."""
    cursor, out, log = loop.Cursor(), np.zeros((1, loop.COLUMNS)), np.zeros((1, 8))
    start = int(arrays.starts[0])
    queued = hasattr(agent, "queue")
    per_step = 1 + int(agent.hp.planning_steps)
    updates = steps = 0
    last = None
    while steps < most:
        log[0, 7] = 0.0
        done, played = loop.play(agent, arrays, cursor, 1, most - steps, out, log)
        made = int(log[0, 7]) if queued else played * per_step
        updates += made
        steps += played
        if not (done and made):
            continue
        q = agent.action_values(slice(None))
        if last is None or not np.array_equal(q, last):
            if _optimal(q, model, good, start):
                return float(updates), False
            last = q.copy()
    return float(updates), True


def _optimal(q: np.ndarray, model: FiniteMDP, good: np.ndarray, start: int) -> bool:
    """Whether every greedy move (ties all taken) from `start` on is an optimal one."""
    seen, todo = {start}, [start]
    while todo:
        s = todo.pop()
        best = np.flatnonzero(q[s] == q[s].max())
        if not good[s, best].all():
            return False
        for a in best:
            if not model.terminal[s, a, 0]:
                nxt = int(model.next_state[s, a, 0])
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
    return True


FIGURES = (fig_8_2, fig_8_4, fig_8_5, example_8_4)
