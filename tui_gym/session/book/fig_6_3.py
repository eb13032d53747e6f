"""Figure 6.3 (Example 6.5): Sarsa on Windy GridWorld, episodes completed against time steps."""

from __future__ import annotations

from tui_gym.core.mdp import FiniteMDP, evaluate, solve
from tui_gym.games import game_named
from tui_gym.games.planning import PlanModel
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Progress,
)
from tui_gym.session.book.runs import (
    LENGTH,
    Learner,
    above,
    completed,
    one_run,
    per_time_step,
    play,
)

# The book's settings: ε = 0.1 throughout, α = 0.5, Q starting at 0, undiscounted.
EPSILON = 0.1
SETTINGS = {"learning_rate": 0.5, "learning_rate_schedule": "constant", "discount": 1.0,
            "epsilon_start": EPSILON, "epsilon_final": EPSILON}
STEPS = 8000  # the figure's time steps
FIRST = 20  # episodes compared at the start and at the end


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    (rook,) = play(FIGURE, "windy", (Learner("Sarsa", "sarsa", SETTINGS),), options, progress,
                   measure=LENGTH)
    (king,) = play(FIGURE, "windy-king", (Learner("Sarsa, king's moves", "sarsa", SETTINGS),),
                   options, progress, measure=LENGTH)
    reach = min(STEPS, int(rook.values.sum(axis=1).min()))
    by_then = completed(rook, [reach])[:, 0]
    count = min(FIRST, rook.values.shape[1] // 2)
    checks = (
        _shortest("the shortest path takes 15 steps", 15, "windy"),
        _shortest("with king's moves (Exercise 6.9), 7", 7, "windy-king"),
        Check("exploring with ε = 0.1 on the optimal policy, an episode takes about 17 steps",
              17, round(_epsilon_greedy_length(), 2), abs(_epsilon_greedy_length() - 17) < 0.5),
        one_run(f"episodes completed by {reach} time steps", 170 * reach / STEPS, by_then,
                digits=0),
        above(f"episodes get shorter: the first {count} against the last {count} (steps)",
              "the slope rises", rook.values[:, :count].mean(axis=1),
              rook.values[:, -count:].mean(axis=1)),
    )
    optimal = int((rook.final == rook.optimum).sum()) if rook.final is not None else 0
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=rook.runs,
        charts=(Chart("episodes completed", "time steps",
                      (per_time_step(rook, until=STEPS), per_time_step(king, until=STEPS))),),
        checks=checks,
        notes=(f"ε = {EPSILON} throughout, α = 0.5, Q starting at 0; the book's figure is one "
               "run, so its count is checked against the spread of one run",
               f"after the last episode the greedy policy takes the shortest path in {optimal} "
               f"of {rook.runs} runs: with α = 0.5 the values stay noisy, and some greedy "
               "policies walk into the wind for ever",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
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


FIGURE = BookFigure(
    name="6.3",
    title="Sarsa on Windy GridWorld (Example 6.5): episodes completed against time steps",
    about="The first episode takes thousands of steps; as Sarsa learns, each takes fewer and "
          "the curve steepens towards one episode every 17 or so steps: the 15-step path "
          "plus exploration. With king's moves the path is 7 steps.",
    world="windy",
    run=run,
    runs=20,
    episodes=200,
    aliases=("example 6.5",),
)
