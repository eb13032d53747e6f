"""The `tui-gym benchmark` sub-command: its flags, running a benchmark, the leaderboard."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from functools import partial
from typing import Any

from rich import box
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from tui_gym.cli.output import key_value_table, print_json
from tui_gym.core.text import visible


def add_parser(sub: Any) -> None:
    """Add `benchmark` to the sub-command parsers `sub`."""
    from tui_gym.cli.flags import (
        add_param_flag,
        add_seed_flag,
        add_wrapper_flag,
        finite_number,
        positive_int,
    )
    from tui_gym.cli.replay_command import add_record_option
    from tui_gym.cli.runs_command import add_history_flags

    bench = sub.add_parser(
        "benchmark",
        help="score a player (a program, random, optimal, a saved agent) on fixed seeds",
        description="Play N episodes of GAME (episode i on seed S+i) with a player and score "
        "it against the exact optimum: mean return and exact regret per episode with 95% "
        "intervals, agreement with the optimal action, invalid actions, time-outs and time "
        "per decision. A program player speaks the JSON-lines protocol of `tui-gym play GAME "
        "--jsonl`, writing requests on its stdout and reading answers on its stdin; an "
        "invalid or late action is replaced by the game's first legal action.",
    )
    bench.add_argument("game", metavar="GAME", help="a game from `tui-gym envs`")
    who = bench.add_mutually_exclusive_group()
    who.add_argument("--agent-cmd", metavar="CMD",
                     help="a program that plays through the JSON-lines protocol")
    who.add_argument("--agent", metavar="NAME",
                     help="a built-in player (random, optimal) or a saved agent file (.tgym)")
    bench.add_argument("--name", metavar="NAME",
                       help="the player's name in the results and the leaderboard (default: "
                       "the command, or the built-in's or agent file's name)")
    bench.add_argument("--episodes", type=positive_int, default=1000, metavar="N",
                       help="episodes to play (default 1,000)")
    add_seed_flag(bench, "bench_seed", "seed of the first episode (default 0)")
    bench.add_argument("--decision-timeout", type=finite_number, default=5.0, metavar="SEC",
                       help="seconds a program has for each decision (default 5)")
    bench.add_argument("--allow-hints", action="store_true",
                       help="answer the player's hint requests (refused by default)")
    add_param_flag(bench)
    add_wrapper_flag(bench)
    bench.add_argument("--leaderboard", action="store_true",
                       help="list GAME's recorded benchmarks, best first, instead of running one")
    add_history_flags(bench, "the result")
    bench.add_argument("--json", action="store_true")
    add_record_option(bench)


def _player(args: argparse.Namespace, game: str) -> tuple[Any, dict[str, Any], tuple[str, ...]]:
    """The player, and the game's parameters and wrappers it plays with."""
    from tui_gym.benchmark.players import AgentPlayer, OptimalPlayer, ProcessPlayer, RandomPlayer
    from tui_gym.cli.flags import key_values
    from tui_gym.session.arena import find_game

    params: dict[str, Any] = key_values(args.params, "--param")
    wrappers = tuple(args.wrapper)
    if args.agent_cmd is not None:
        return ProcessPlayer(args.agent_cmd), params, wrappers
    if args.agent is None:
        raise ValueError("name a player: --agent-cmd CMD, or --agent random, optimal or a "
                         "saved agent file")
    if args.agent in ("random", "optimal"):
        player = RandomPlayer(args.bench_seed) if args.agent == "random" else OptimalPlayer()
        return player, params, wrappers
    agent = AgentPlayer(args.agent, args.bench_seed)
    agent.check_game(find_game(game).env_id)
    if params or wrappers:
        raise ValueError("a saved agent plays the game as it was saved: drop --param and "
                         "--wrapper")
    session = agent.session
    return agent, dict(session.env_kwargs), tuple(str(c) for c in session.applied)


def cmd_benchmark(args: argparse.Namespace, out: Console) -> int:
    if args.leaderboard:
        return _show_leaderboard(args, out)
    if not args.decision_timeout > 0:
        raise ValueError("--decision-timeout must be a positive number of seconds")
    from tui_gym.benchmark.results import record, run_benchmark
    from tui_gym.cli.replay_command import open_recorder
    from tui_gym.core.engine.processes import handling

    recorder = None if args.record is None else partial(
        open_recorder, args.record, source="benchmark", seed=args.bench_seed)
    player, params, wrappers = _player(args, args.game)
    if args.name is not None:
        if not args.name.strip():
            raise ValueError("--name cannot be empty")
        player.label = args.name.strip()
    def leave(signum: int, frame: Any) -> None:  # an exit, so the `finally` clauses run
        raise SystemExit(128 + signum)

    # SIGTERM and SIGHUP end the player's program as ctrl+c does.
    with handling(("SIGTERM", "SIGHUP"), leave):
        result = run_benchmark(
            args.game, player, episodes=args.episodes, seed=args.bench_seed, params=params,
            wrappers=wrappers, decision_timeout=args.decision_timeout,
            allow_hints=args.allow_hints, recorder=recorder,
        )
    recorded = unrecorded = ""
    if not args.no_record:
        from tui_gym.core.experiments import RunHistoryError, resolve_db_path

        try:  # a history that fails (a full disk) must not lose the result: said after it
            run_id = record(result, args.db)
        except RunHistoryError as exc:
            unrecorded = f"tui-gym: this result was not recorded in the run history: {exc}\n"
        else:
            result = replace(result, run_id=run_id)
            recorded = f"recorded as run {run_id} in {resolve_db_path(args.db)}"
    if args.json:
        print_json("benchmark", result.to_json())
    else:
        out.print(key_value_table(f"Benchmark: {result.game}",
                                  [(label, escape(value)) for label, value in result.rows()]))
        if recorded:
            out.print(escape(recorded))
    sys.stderr.write(unrecorded)
    return 0


def _show_leaderboard(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.benchmark.results import leaderboard
    from tui_gym.session.arena import find_game

    game = find_game(args.game).name
    path, standings = leaderboard(game, args.db)
    if args.json:
        print_json("benchmark", {"game": game, "db": path,
                                 "runs": [{"rank": rank, **run.to_json()}
                                          for rank, run in enumerate(standings, 1)]})
        return 0
    if not standings:
        out.print(escape(f"no benchmark of {game} is recorded in {path} yet"))
        return 0
    table = Table(title=f"Leaderboard: {game}, best first", title_justify="left",
                  box=box.SIMPLE_HEAD, show_edge=False, pad_edge=False,
                  padding=(0, 1, 0, 0))
    table.add_column("#", justify="right", no_wrap=True)
    table.add_column("player", overflow="fold", min_width=12)
    for name in ("episodes", "mean return", "regret/ep.", "optimal", "bad/late", "ms"):
        table.add_column(name, justify="right", no_wrap=True)
    for rank, run in enumerate(standings, 1):
        table.add_row(
            str(rank), escape(visible(run.algorithm, 60)), _figure(run, "episodes"),
            _figure(run, "mean_return", "+.3f"), _figure(run, "regret_per_episode", ".3f"),
            _figure(run, "agreement", ".1%"),
            f"{_figure(run, 'invalid_actions')}/{_figure(run, 'timeouts')}",
            _figure(run, "decision_ms_median", ".2f"),
        )
    out.print(table)
    out.print(escape(f"from {path}; bad/late: invalid actions and time-outs; "
                     "ms: median time per decision"))
    return 0


def _figure(run: Any, name: str, shown: str = ",.0f") -> str:
    """A recorded figure as '-0.036±0.042' ('–' when the run has none)."""
    figure = run.figure(name)
    if figure is None:
        return "–"
    ci95 = "" if figure.ci95 is None else f"±{figure.ci95:{shown.lstrip('+')}}"
    return f"{figure.value:{shown}}{ci95}"
