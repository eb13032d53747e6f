"""The headless sub-commands of `tui-gym`, each a thin call into the core: `cmd_NAME(args,
console) -> exit code` runs `tui-gym NAME`."""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from tui_gym.algorithms import ALGORITHMS, COMMON_PARAMS, Field, algorithm
from tui_gym.cli.flags import flag, game_kwargs, hyperparameters, wrapper_choices
from tui_gym.cli.output import CliError, cli_errors, key_value_table, print_json, say_status
from tui_gym.core.params import Param, typed_text
from tui_gym.games import GAMES, game_for, resolve_env_id
from tui_gym.session import evaluation
from tui_gym.session.evaluation import EvalReport
from tui_gym.session.session import TARGET_GAP_BUDGET_FACTOR, Session, default_settings

WRAPPER_SYNTAX = "--wrapper NAME or --wrapper NAME:key=value,key=value, repeatable; the " \
    "first is innermost"


def _param_dict(param: Field) -> dict[str, Any]:
    data: dict[str, Any] = {"name": param.name, "type": "choice", "default": param.default}
    if isinstance(param, Param):  # else a Choice: one word out of a few
        data.update(type=param.kind.__name__, minimum=param.minimum, maximum=param.maximum)
    data.update(range=param.describe_range(), help=param.help)
    if param.choices:
        data["choices"] = list(param.choices)
    return data


def _default_text(field: Field) -> str:
    """A parameter's default and what it takes: `=100 in [1, 100000]`, `=true (true or false)`."""
    allowed = field.describe_range()
    where = f"in {allowed}" if allowed[:1] in "[(" else f"({allowed})"
    return f"={typed_text(field.default)} {where}"


def cmd_envs(args: argparse.Namespace, out: Console) -> int:
    if args.json:
        print_json("envs", {"envs": [
            {"name": g.name, "env_id": g.env_id, "other_ids": list(g.other_ids), "key": g.key,
             "actions": list(g.action_names), "description": g.description, "teaches": g.teaches,
             "params": [_param_dict(param) for param in g.params]}
            for g in GAMES
        ]})
        return 0
    # One block a game, so nothing is cut on a narrow terminal.
    out.print("[bold]Games[/]")
    for g in GAMES:
        ids = ", ".join((g.env_id, *g.other_ids))
        key = f"  (key {g.key} in the app)" if g.key else ""
        out.print(f"\n[bold cyan]{g.name}[/]  {escape(ids)}{escape(key)}", overflow="fold")
        out.print(f"  {escape(g.description)}", overflow="fold")
        if g.teaches:
            out.print(f"  [dim]teaches:[/] {escape(g.teaches)}", overflow="fold")
        out.print(f"  [dim]actions:[/] {', '.join(g.action_names)}", overflow="fold")
        for p in g.params:
            out.print(f"  {flag(p.name)} {escape(p.describe_range())}, default "
                      f"{typed_text(p.default)}: {escape(p.help)}", overflow="fold")
    out.print("\nAny other Gymnasium id with Discrete spaces and a transition table P works "
              "too (MODULE:ID imports the module that registers it).", overflow="fold")
    return 0


def cmd_wrappers(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.core.wrappers import CATALOG

    if args.json:
        print_json("wrappers", {"wrappers": [
            {"name": spec.name, "summary": spec.summary,
             "changes_observation": spec.changes_observation,
             "params": [_param_dict(param) for param in spec.params]}
            for spec in CATALOG.values()
        ], "syntax": WRAPPER_SYNTAX})
        return 0
    if out.width < 80:  # too narrow for three columns: one block a wrapper
        out.print("[bold]Wrapper catalog[/]")
        for spec in CATALOG.values():
            out.print(f"\n[bold cyan]{spec.name}[/]")
            out.print(escape(spec.summary), overflow="fold")
            for p in spec.params:
                out.print(f"  {p.name}{escape(_default_text(p))}", overflow="fold")
    else:
        table = Table(title="Wrapper catalog", title_justify="left", show_lines=True)
        table.add_column("name", style="bold cyan", no_wrap=True)
        table.add_column("what it changes and teaches", ratio=1, overflow="fold")
        # Parameter names are typed after --wrapper: never cut, each on a line of its own.
        longest = max((len(p.name) for spec in CATALOG.values() for p in spec.params), default=1)
        table.add_column("parameters (default, range)", min_width=longest, overflow="fold")
        for spec in CATALOG.values():
            params = "\n".join(f"{p.name}\n  {_default_text(p)}" for p in spec.params) or "-"
            table.add_row(spec.name, escape(spec.summary), escape(params))
        out.print(table)
    out.print(f"Use with {WRAPPER_SYNTAX}.\nExample: tui-gym train GAME --wrapper "
              "TimeLimit:max_episode_steps=50 --wrapper StepPenalty:penalty=0.01")
    return 0


def cmd_algorithms(args: argparse.Namespace, out: Console) -> int:
    if args.json:
        print_json("algorithms", {"algorithms": [
            {"name": cls.name, "title": cls.title, "summary": cls.summary, "target": cls.formula,
             "params": [_param_dict(field) for field in cls.params]}
            for cls in ALGORITHMS
        ]})
        return 0
    table = Table(title="Algorithms", title_justify="left", show_lines=True)
    table.add_column("name", style="bold cyan", no_wrap=True)
    table.add_column("what it teaches", ratio=1, overflow="fold")
    table.add_column("target", overflow="fold")
    table.add_column("its own parameters (default, range)", overflow="fold")
    common = {field.name for field in COMMON_PARAMS}
    for cls in ALGORITHMS:
        own = "\n".join(f"{f.name}\n  {_default_text(f)}" for f in cls.params
                        if f.name not in common) or "-"
        table.add_row(cls.name, escape(f"{cls.title}: {cls.summary}"), escape(cls.formula),
                      escape(own))
    out.print(table)
    shared = ", ".join(field.name for field in COMMON_PARAMS)
    out.print(f"Every algorithm also takes {shared}.", overflow="fold")
    out.print("Use with [bold]tui-gym train ENV --algorithm NAME[/]; each game has its own "
              "defaults per algorithm (see the README).")
    return 0


def _check_fit(session: Session, env_id: str) -> None:
    if session.skipped:
        reasons = "; ".join(reason for _, reason in session.skipped)
        raise CliError(f"wrapper does not fit {env_id}: {reasons}")


def _session_from_args(args: argparse.Namespace) -> Session:
    env_id = resolve_env_id(args.env)
    game = game_for(env_id)
    choices = wrapper_choices(args.wrapper)
    with cli_errors(ValueError, prefix="--algorithm: "):
        cls = algorithm(args.algorithm)
    kwargs = game_kwargs(args, game)
    hp = hyperparameters(args, cls)
    if args.target_gap is not None and "episodes" not in hp:
        # Five times the game's budget: a longer budget decays epsilon more slowly, and the
        # run stops at the target anyway.
        defaults = default_settings(game, cls.name, game.normalize_kwargs(kwargs))
        hp["episodes"] = TARGET_GAP_BUDGET_FACTOR * int(defaults.episodes)
    try:
        session = Session(
            env_id=env_id, env_kwargs=kwargs, choices=choices, hp=hp, seed=args.train_seed,
            engine=args.engine, algorithm=cls.name,
        )
    except ValueError as exc:
        text = str(exc)
        for name in hp:  # e.g. epsilon_final above epsilon_start: say it with the flags
            text = text.replace(name, flag(name))
        raise CliError(text) from None
    _check_fit(session, env_id)
    session.trainer.on_status = say_status
    return session


def eval_dict(session: Session, report: EvalReport) -> dict[str, Any]:
    """The JSON object `eval --json` prints (and `train --json` nests): the sampled
    figures of greedy play and, where the game has an exact model, the greedy policy's
    `exact_value` beside the `optimal_value` and their `gap` (else `exact_reason`)."""
    data: dict[str, Any] = {
        "env_id": session.env_id, "algorithm": session.algorithm, **report.to_dict()
    }
    if report.requested is not None:
        data["step_budget"] = evaluation.EVAL_STEP_BUDGET
    ref = session.evaluation_reference()
    if ref is not None:
        data.update(ref.figures)
        if ref.scope.note:  # what the exact figures take into account, or that they cannot
            data["reference_note"] = ref.scope.note
    else:
        data["exact_reason"] = session.exact_reason() or "no exact model of this game"
    return data


# Rows of the exact figures, first, with their labels.
_EXACT_ROWS = (("exact_value", "exact value (greedy policy)"), ("optimal_value", "optimal value"),
               ("gap", "gap to the optimum"))
_PERCENT = ("win_rate", "draw_rate", "loss_rate", "success_rate", "optimal_pair_fraction",
            "timeout_rate", "delivered_rate", "terminated_rate")
_NOT_ROWS = ("env_id", "episodes", "episodes_requested", "mean_return", "std_return",
             "step_budget", "exact_reason", "reference_note", "algorithm", *dict(_EXACT_ROWS))


def _eval_rows(data: dict[str, Any]) -> list[tuple[str, str]]:
    rows = [(label, f"{data[key]:.4f}" if key == "gap" else f"{data[key]:+.4f}")
            for key, label in _EXACT_ROWS if isinstance(data.get(key), float)]
    if "exact_reason" in data:
        rows.append(("exact value", f"n/a ({data['exact_reason']})"))
    if data.get("reference_note"):
        rows.append(("exact figures", str(data["reference_note"])))
    played = f"{data['episodes']:,}"
    requested = data.get("episodes_requested", data["episodes"])
    if requested != data["episodes"]:
        budget = data.get("step_budget", evaluation.EVAL_STEP_BUDGET)
        played += f" of {requested:,} (stopped at the {budget:,}-step budget)"
    rows += [
        ("sampled episodes", played), ("sampled mean return", f"{data['mean_return']:+.4f}"),
        ("sampled std of return", f"{data['std_return']:.4f}"),
    ]
    return rows + [(key.replace("_", " "), _value_text(key, value))
                   for key, value in data.items() if key not in _NOT_ROWS]


def _value_text(key: str, value: Any) -> str:
    if value is None:
        return "n/a"
    if key in _PERCENT:
        return f"{value:.2%}"
    return f"{value:+.4f}" if isinstance(value, float) else str(value)


def cmd_train(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.cli.output import warn
    from tui_gym.session.experiments.train_recording import TrainRecording

    enabled = not (args.no_record or getattr(args, "no_history", False))
    with TrainRecording(getattr(args, "db", None), enabled=enabled, warn=warn) as recording:
        return _train(args, out, recording)


def _train(args: argparse.Namespace, out: Console, recording: Any) -> int:
    """`train`, its run recorded by `recording` (the run history's `TrainRecording`)."""
    from tui_gym.core.wrappers import format_wrapper_spec, get_spec

    if args.target_gap is not None and args.target_gap <= 0:
        raise CliError(f"--target-gap must be a positive number, got {args.target_gap:g}")
    session = _session_from_args(args)
    if args.follow is not None:
        epsilon = float(hyperparameters(args, session.learner_class).get("epsilon_final", 0.0))
        with cli_errors(ValueError, prefix="--follow: "):
            session.follow(Session.load(args.follow), epsilon)
    recording.begin(session)
    hp = session.hp
    assert hp is not None  # a built session has its hyperparameters
    started = time.perf_counter()
    if args.json or not out.is_terminal:
        outcome = session.train(target_gap=args.target_gap, on_chunk=recording.on_chunk)
    else:
        from tui_gym.cli.output import progress_bar

        bar = progress_bar(out, "[bold]training[/]", "bar", "count", "percent",
                           "{task.fields[rate]:>11,.0f} ep/s",
                           "mean return {task.fields[mean]:+.3f}", "elapsed", "left",
                           transient=False)
        task = bar.add_task("train", total=hp.episodes, rate=0.0, mean=0.0)

        def update(snap: Any) -> None:
            rate = snap.episodes / snap.seconds if snap.seconds else 0.0
            bar.update(task, completed=snap.episodes, rate=rate, mean=snap.mean_return)

        with bar:
            outcome = session.train(target_gap=args.target_gap, on_chunk=recording.chain(update))
    seconds = time.perf_counter() - started
    trainer = session.trainer
    report = session.evaluate(args.eval_episodes, seed=args.train_seed + 1)
    evaluation = eval_dict(session, report)
    saved = str(session.save(args.save)) if args.save is not None else None  # `output_file`
    run_id = recording.finish(report, saved)
    # Each applied wrapper with all its parameters (defaults filled in), innermost first.
    wrappers = [{"name": c.name, "params": get_spec(c.name).validate(c.values()),
                 "spec": format_wrapper_spec(c)} for c in session.applied]
    data = {
        "env_id": session.env_id, "env_kwargs": session.env_kwargs, "algorithm": session.algorithm,
        "wrappers": wrappers, "engine": trainer.engine,
        "engine_reason": session.engine_reason, "episodes": trainer.episodes,
        "steps": trainer.steps, "seconds": seconds,
        "episodes_per_second": trainer.episodes / seconds if seconds else None,
        "hyperparameters": hp.to_dict(), "rolling_mean_return": trainer.latest.mean_return,
        "eval": evaluation, "saved": saved, "run": run_id,
    }
    if args.target_gap is not None:
        data.update(target_gap=args.target_gap, reached_target=outcome.reached_target,
                    checked_gap=outcome.gap)
    if session.predicts:
        figures = session.prediction()  # per reached model state, the estimate and the truth
        if figures is None:
            data.update(rms_error=None, rms_reason=session.prediction_reason())
        else:
            data.update(rms_error=figures.rms, prediction={
                "states": list(figures.states), "estimate": list(figures.estimate),
                "truth": list(figures.truth)})
    if args.json:
        print_json("train", data)
        return 0
    rows = [
        ("env", f"{session.env_id} {session.env_kwargs or ''}".strip()),
        ("algorithm", session.learner_class.title), ("wrappers", session.chain_repr()),
        ("engine", session.engine_reason), ("episodes", f"{trainer.episodes:,}"),
        ("steps", f"{trainer.steps:,}"), ("seconds", f"{seconds:.2f}"),
        ("episodes/s", f"{data['episodes_per_second']:,.0f}"),
        (f"rolling mean return ({trainer.latest.window})", f"{trainer.latest.mean_return:+.4f}"),
    ]
    if args.target_gap is not None:
        verdict = "reached" if outcome.reached_target else "NOT reached"
        rows.append(("target gap", f"{args.target_gap:g} {verdict} (gap {outcome.gap:.4f})"))
    if session.predicts:
        rms = data["rms_error"]
        rows.append(("RMS error of V (exact V^π)", f"{rms:.4f}" if rms is not None
                     else f"n/a ({data['rms_reason']})"))
    rows += _eval_rows(evaluation)
    if saved:
        rows.append(("saved to", saved))
    if run_id is not None:
        rows.append(("run history", f"run {run_id} in {recording.path}"))
    out.print(key_value_table("Training summary", rows))
    reference = None if session.predicts else session.reference()  # a fixed policy: no bound
    if reference is not None and session.shortfall(reference):  # why it ends short, if it does
        out.print(session.shortfall(reference), markup=False)
    return 0


def cmd_eval(args: argparse.Namespace, out: Console) -> int:
    session = Session.load(args.path)
    data = eval_dict(session, session.evaluate(args.episodes, seed=args.eval_seed))
    if args.json:
        print_json("eval", data)
        return 0
    out.print(key_value_table("Evaluation", [
        ("file", args.path), ("env", session.env_id), ("algorithm", session.learner_class.title),
        ("wrappers", session.chain_repr()), *_eval_rows(data)]))
    return 0


def cmd_optimal(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.core.mdp import NotAvailable
    from tui_gym.games.words import signed

    env_id = resolve_env_id(args.env)
    game = game_for(env_id)
    kwargs = game.normalize_kwargs(game_kwargs(args, game))
    optimum = game.oracle.optimum(kwargs)
    if isinstance(optimum, NotAvailable):
        raise CliError(optimum.reason)
    names, states = game.action_names, game.states.base_observations(kwargs)
    if args.json:
        data: dict[str, Any] = {"env_id": env_id, "env_kwargs": kwargs,
                                "optimal_value": optimum.value, "meaning": optimum.summary,
                                **optimum.figures}
        q, marks = optimum.q, optimum.marks
        if q is not None and marks is not None and not isinstance(states, NotAvailable):
            data["policy"] = [
                {"state": game.states.json_observation(obs),
                 "actions": [names[a] for a in np.flatnonzero(marked)],
                 "value": float(np.max(values))}
                for obs, values, marked in zip(states, q, marks, strict=True)
            ]
        print_json("optimal", data)
        return 0
    shown = game.solution(kwargs)  # action values that point the optimal moves
    if not isinstance(shown, NotAvailable) and shown.q is not None:
        layout = game.layout
        for panel in layout.heatmaps(np.asarray(shown.q), kwargs, layout.default_focus(kwargs),
                                     shown.marks):
            out.print(_panel_table(panel))
    # An edited map's text is shown as its size; its rows are in the table above.
    rules = ", ".join(f"{k}={v}" if k != "layout" else f"a {game.grid_map(kwargs).size_text} map"
                      for k, v in kwargs.items())
    out.print(f"{game.title}{f' ({rules})' if rules else ''}: {optimum.summary}.")
    out.print(f"Exact value of the optimum: [bold]{signed(optimum.value, 5)}[/]")
    for name, value in optimum.figures.items():
        out.print(f"{name.replace('_', ' ').capitalize()}: {value:.5g}")
    return 0


def _panel_table(panel: Any) -> Table:
    """A heatmap panel of the optimum as a table of its cells' labels."""
    table = Table(title=panel.title, title_justify="left")
    table.add_column("", justify="right", style="bold")
    for label in panel.col_labels:
        table.add_column(label, justify="center")
    for row_label, labels, marked in zip(panel.row_labels, panel.labels, panel.marked.tolist(),
                                         strict=True):
        table.add_row(row_label, *(escape(text) + ("*" if mark else "")
                                   for text, mark in zip(labels, marked, strict=True)))
    table.caption = panel.legend or None
    return table


def cmd_play(args: argparse.Namespace, out: Console) -> int:
    import sys

    from tui_gym.session.protocol import JsonlPlayer, serve

    env_id = resolve_env_id(args.env)
    session = Session(env_id=env_id, env_kwargs=game_kwargs(args, game_for(env_id)),
                      choices=wrapper_choices(args.wrapper), seed=args.play_seed or 0)
    _check_fit(session, env_id)
    player = JsonlPlayer(session, seed=args.play_seed)
    if args.record is None:
        return serve(player, sys.stdin.buffer, sys.stdout)
    from tui_gym.cli.replay_command import open_recorder

    with open_recorder(args.record, session, source="play", seed=args.play_seed) as recorder:
        player.game.recorder = recorder
        return serve(player, sys.stdin.buffer, sys.stdout)


def cmd_screenshots(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.ui.screenshots import write_screenshots

    paths = [str(path) for path in write_screenshots(args.directory)]
    if args.json:
        print_json("screenshots", {"written": paths})
        return 0
    for path in paths:
        out.print(f"wrote {path}")
    return 0


def cmd_bench(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.bench.report import notes, table, to_json
    from tui_gym.bench.run import run_bench

    names = None
    if args.algorithm is not None:
        with cli_errors(ValueError, prefix="--algorithm: "):
            names = (algorithm(args.algorithm).name,)
    # Plain lines, not a spinner: a spinner's refresh thread would share the GIL
    # with the thread runner being measured.
    err, started = Console(stderr=True), time.perf_counter()
    results = run_bench(quick=args.quick, algorithms=names, progress=None if args.json else (
        lambda text: err.print(f"[dim]{time.perf_counter() - started:5.1f} s[/] {text}")))
    if args.json:
        print_json("bench", to_json(results))
        return 0
    out.print(table(results))
    for line in notes(results):
        out.print(line)
    return 0
