"""Figure 6.2 (Example 6.2): TD(0) against constant-α Monte Carlo on the 5-state random walk,
the RMS error of V against the true values over episodes."""

from __future__ import annotations

from tui_gym.session.book.figure import BookFigure, Chart, FigureOptions, FigureResult, Progress
from tui_gym.session.book.prediction_runs import play_prediction
from tui_gym.session.book.runs import Learner, above, below, per_episode

TD_ALPHAS = (0.15, 0.1, 0.05)
MC_ALPHAS = (0.01, 0.02, 0.03, 0.04)
START = 0.5  # every estimate starts half-way, as the book's do
LEARNERS = (
    *(Learner(f"TD α={a:g}", "td0", {"learning_rate": a, "initial_value": START})
      for a in TD_ALPHAS),
    *(Learner(f"MC α={a:g}", "mc-prediction", {"learning_rate": a, "initial_value": START})
      for a in MC_ALPHAS),
)
LATE = 25  # the last episodes, where the curves have settled


def run(options: FigureOptions, progress: Progress) -> FigureResult:
    played = play_prediction(FIGURE, 5, LEARNERS, options, progress)
    late = {p.label: p.values[:, -LATE:].mean(axis=1) for p in played}
    td = [late[x.label] for x in LEARNERS[: len(TD_ALPHAS)]]
    mc = [late[x.label] for x in LEARNERS[len(TD_ALPHAS):]]
    best_td, best_mc = min(td, key=lambda v: v.mean()), min(mc, key=lambda v: v.mean())
    checks = (
        below(f"TD(0) ends lower than constant-α MC, each at its best α (mean RMS error of "
              f"the last {LATE} episodes)", "TD lower", best_td, best_mc, digits=3),
        above(f"A larger step settles higher: TD(0) with α = {TD_ALPHAS[0]:g} against "
              f"{TD_ALPHAS[-1]:g} (last {LATE} episodes)", "higher", td[0], td[-1], digits=3),
    )
    return FigureResult(
        figure=FIGURE.name, title=FIGURE.title, runs=played[0].runs,
        charts=(Chart("RMS error of V, averaged over the 5 states", "episodes",
                      tuple(per_episode(p) for p in played)),),
        checks=checks,
        notes=("the random policy's values 1/6 … 5/6, from policy evaluation on the model; "
               f"V starts at {START:g}, undiscounted",
               "bands: 95% intervals of the mean over runs; verdicts: 99% intervals"),
    )


FIGURE = BookFigure(
    name="6.2",
    title="TD(0) against constant-α MC on the random walk (Example 6.2): RMS error",
    about="Both learn the random policy's values on the 5-state walk; TD(0), bootstrapping "
          "from the next state's estimate, gets closer in fewer episodes than Monte Carlo "
          "at every step size shown. A larger step learns faster at first and settles "
          "higher.",
    world="random-walk",
    run=run,
    runs=100,
    episodes=100,
    aliases=("example 6.2",),
)
