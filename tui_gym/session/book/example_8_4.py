"""Example 8.4: prioritized sweeping against Dyna-Q on ever finer Dyna mazes, updates until
the greedy policy is optimal."""

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
    FigureStopped,
    Progress,
    heading,
)
from tui_gym.session.book.runs import Learner, Played, below, counts, margin, swept, world_phases
from tui_gym.session.experiments.compare import Arm, Setup, prepare

# The book: "both systems made at most n = 5 updates per environmental interaction"; the
# rest as in Example 8.1 (ε = 0.1, γ = 0.95), with α = 1 (a deterministic maze: each update
# takes the model's target whole) and θ = 0.0001.
PLANNING = 5
SETTINGS = {"learning_rate": 1.0, "learning_rate_schedule": "constant", "discount": 0.95,
            "epsilon_start": 0.1, "epsilon_final": 0.1, "planning_steps": PLANNING}
LEARNERS = (Learner("Dyna-Q", "dyna-q", SETTINGS),
            Learner("Prioritized sweeping", "prioritized-sweeping", {**SETTINGS, "theta": 0.0001}))
SCALES = (1, 2, 4)  # each cell of the Dyna maze made scale x scale cells: 47 to 752 states
FULL_SCALES = (1, 2, 4, 8)  # to 3008 states, the book's axis doubling twice a step
STEPS_PER_STATE = 10_000  # real steps a run may take to become optimal, per state
FACTOR = 5  # the book: prioritized sweeping finds optimal solutions "often by a factor of
# 5 to 10" faster


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    runs, _ = counts(FIGURE, options)
    scales = FULL_SCALES if options.full else SCALES
    updates = np.zeros((len(LEARNERS), len(scales), runs))
    sizes: list[int] = []
    unfinished = [0] * len(LEARNERS)
    total = len(LEARNERS) * len(scales) * runs
    for j, scale in enumerate(scales):
        model, good, hps, cells = _maze(scale, runs, options.seed)
        sizes.append(cells)
        arrays = loop.ModelArrays.of(model)
        for i, (learner, hp) in enumerate(zip(LEARNERS, hps, strict=True)):
            for r in range(runs):
                if options.stop is not None and options.stop.is_set():
                    raise FigureStopped(f"{heading(FIGURE.name)} stopped")
                done = (j * len(LEARNERS) + i) * runs + r
                progress(done, total, f"{sizes[-1]} states: {learner.label}, run {r + 1}")
                cls = algorithm(learner.algorithm)
                agent = cls(model.n_actions, cls.settings(hp), n_states=model.n_states,
                            seed=options.seed + r)
                updates[i, j, r], late = _updates_until_optimal(agent, arrays, model, good,
                                                                STEPS_PER_STATE * cells)
                unfinished[i] += late
    progress(total, total, "done")
    played = [[Played(learner.label, updates[i, j][:, np.newaxis], None, None)
               for j in range(len(scales))] for i, learner in enumerate(LEARNERS)]

    def log_updates(values: np.ndarray) -> np.ndarray:
        return np.log10(values[:, 0])

    series = tuple(swept(learner.label, sizes, rows, log_updates)
                   for learner, rows in zip(LEARNERS, played, strict=True))
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
        figure=FIGURE.name, title=FIGURE.title, runs=runs,
        charts=(Chart("log10 updates until the greedy policy is optimal", "states", series),),
        checks=tuple(checks),
        notes=(f"ε = 0.1, γ = 0.95, α = 1, at most {PLANNING} updates a step (Dyna-Q: "
               f"its own and {PLANNING} planned; prioritized sweeping: what it takes from "
               "its queue, θ = 0.0001)",
               "optimal: from the start, every greedy move (ties all counted) is on a "
               "shortest way to the goal, checked after each episode against the exact "
               "optimum",
               "log10 of Dyna-Q's updates over prioritized sweeping's, by size: "
               + ", ".join(f"{size} states {g:.2f}" for size, g in zip(sizes, gap.mean(axis=1),
                                                                     strict=True)),
               f"runs not optimal within {STEPS_PER_STATE:,} steps a state (counted as they "
               f"stood): Dyna-Q {unfinished[0]}, prioritized sweeping {unfinished[1]}",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


def _maze(scale: int, runs: int,
          seed: int) -> tuple[FiniteMDP, np.ndarray, list[dict[str, Any]], int]:
    """The Dyna maze made `scale` times finer (the game's model, its episode limit), the
    optimal moves (`good[state, action]`), each learner's settings, and its open cells
    (the states the book counts)."""
    params = {"scale": scale}
    prepared = prepare(Setup("dyna-maze", runs, 1, params, (), seed),
                       [Arm(x.algorithm, dict(x.settings), x.label) for x in LEARNERS])
    model = world_phases("dyna-maze", prepared.env_kwargs).models[0]
    steps = model.replace(reward=np.full(model.reward.shape, -1.0), reward_std=None)
    q = solve(with_horizon(steps, None)).q
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
    """The Q updates `agent` makes until its greedy policy is optimal from the start,
    looked at after each episode that changed Q (Dyna-Q: 1 + n a step; prioritized
    sweeping: what it takes from its queue, which its log adds up), and whether it was
    still not optimal after `most` steps."""
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




FIGURE = BookFigure(
    name="example 8.4",
    title="Prioritized sweeping against Dyna-Q on finer Dyna mazes (Example 8.4): updates "
          "until optimal",
    about="The Dyna maze with each cell made 2 x 2 and 4 x 4 cells: the same structure, "
          "more states. Dyna-Q plans from pairs drawn at random, most of whose updates "
          "change nothing; prioritized sweeping plans where values change, backwards from "
          "the goal, and its greedy policy is optimal after many times fewer updates.",
    world="dyna-maze",
    run=run,
    runs=10,
    aliases=("e8.4", "example-8.4"),
)
