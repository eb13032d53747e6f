"""`tui-gym plan GAME`: policy evaluation, policy iteration or value iteration, headless."""

from __future__ import annotations

import argparse

from rich.console import Console

from tui_gym.book_text import panel_text
from tui_gym.cli.flags import add_game_flags, finite_number, game_kwargs
from tui_gym.cli.output import print_json
from tui_gym.core.mdp.planning import METHODS
from tui_gym.games import game_for, resolve_env_id
from tui_gym.session.plan import plan, plan_json
from tui_gym.session.plan.panels import numbered, plan_panels
from tui_gym.session.plan.start import START_POLICIES, saved_agent_q

METHOD_WORDS = {"evaluate": "Policy evaluation", "policy-iteration": "Policy iteration",
                "value-iteration": "Value iteration"}


def add_plan_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser("plan", help="policy evaluation, policy or value iteration, headless")
    parser.add_argument("env", metavar="ENV", help="a game (`tui-gym envs` lists them)")
    parser.add_argument("--method", choices=METHODS, default="value-iteration",
                        help="what to run to its end (default value-iteration)")
    parser.add_argument("--policy", default="random", metavar="random|optimal|PATH",
                        help="the start policy: random (default), optimal, or a saved agent's "
                        "greedy policy (its file)")
    parser.add_argument("--gamma", type=finite_number, metavar="G",
                        help="the discount, in (0, 1] (default: the game's)")
    parser.add_argument("--theta", type=finite_number, default=1e-6, metavar="T",
                        help="stop when the largest change of a sweep is below T (1e-6)")
    parser.add_argument("--in-place", action="store_true",
                        help="sweep in place (one array) instead of synchronously")
    add_game_flags(parser)
    parser.add_argument("--json", action="store_true")


def cmd_plan(args: argparse.Namespace, out: Console) -> int:
    env_id = resolve_env_id(args.env)
    game = game_for(env_id)
    kwargs = game.normalize_kwargs(game_kwargs(args, game))
    start, agent_q = args.policy, None
    if start not in START_POLICIES or start == "agent":
        agent_q, start = saved_agent_q(args.policy, game, kwargs), "agent"
    result = plan(game, kwargs, args.method, start=start, gamma=args.gamma, theta=args.theta,
                  in_place=args.in_place, agent_q=agent_q)
    data = plan_json(result)
    if args.json:
        print_json("plan", data)
        return 0
    model, planner = result.model, result.planner
    focus = game.layout.default_focus(result.kwargs)
    for numbers in (True, False):
        for panel in plan_panels(game, result.kwargs, model, planner.v, planner.policy,
                                 planner.changed, focus, numbers):
            out.print(panel_text(panel, out.width), soft_wrap=True)
    if model.value_panel is not None:
        out.print(panel_text(numbered(model.value_panel(planner.v)), out.width), soft_wrap=True)
    ended = "converged" if result.converged else "stopped before converging"
    sweeps = f"{planner.sweeps:,} {'in-place' if planner.in_place else 'synchronous'} sweeps"
    improvements = f", {planner.iterations} improvements" if result.method == (
        "policy-iteration") else ""
    out.print(f"{METHOD_WORDS[result.method]} on {game.title} from the {result.start} policy: "
              f"{sweeps}{improvements}, {ended} (θ = {planner.theta:g}).")
    out.print(f"Start distribution's value, discounted by γ = {planner.gamma:g} with no limit "
              f"(the book's): [bold]{data['start_value']:+.6g}[/]")
    if model.horizon is not None or planner.gamma < 1.0:
        limit = f"{model.horizon}-step episodes" if model.horizon else "no limit"
        out.print(f"The tool's exact value of this policy (undiscounted, {limit}): "
                  f"[bold]{data['limited_value']:+.6g}[/]")
    return 0
