"""Planning's figures: a value-iteration sweep on Taxi, Jack's car rental solved by policy
iteration, and the Plan view animating sweeps while it answers keys."""

from __future__ import annotations

import asyncio
import random
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tui_gym.bench.figures import timed
from tui_gym.bench.live import SIZE, _until, after_each, on_frames, press

GRID_GAMES = ("gridworld", "frozenlake", "cliffwalking")
SPEED = 5  # the Plan view's 50 sweeps a second


@dataclass(frozen=True)
class ViewFigures:
    """One grid game's Plan view: sweeps drawn a second, and key latencies (ms)."""

    game: str
    sweeps_per_second: float
    keys_ms: tuple[float, ...]


@dataclass(frozen=True)
class DPResult:
    """Planning's figures (see the module docstring)."""

    taxi_sweep_ms: float
    jack_seconds: float
    jack_model_seconds: float
    views: tuple[ViewFigures, ...]


async def _view_once(game: str, seconds: float, presses: int, seed: int) -> ViewFigures:
    from tui_gym.session.session import Session
    from tui_gym.ui.app import TuiGymApp

    app = TuiGymApp(Session(game, seed=seed), tune_gc=True)
    frames: list[float] = []
    drawn: list[tuple[float, int, bool, bool]] = []  # (time, sweeps, in place, numbers)
    on_frames(app, lambda: frames.append(time.perf_counter()))
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("P")
        view = app.plan_view
        assert view is not None
        await _until(lambda: view.runner is not None, "the model")
        after_each(view, "show_snapshot", lambda _, snapshot: drawn.append(
            (time.perf_counter(), snapshot.sweeps, snapshot.in_place, view.numbers)))
        runner = view.runner
        assert runner is not None
        runner.set_method("evaluate")
        runner.set_theta(1e-300)
        runner.set_speed(SPEED)
        runner.run()
        await _until(lambda: runner.latest.running, "the run")
        await asyncio.sleep(0.3)
        start, first = time.perf_counter(), len(drawn)
        await asyncio.sleep(seconds)
        shown = drawn[first:]
        rate = (shown[-1][1] - shown[0][1]) / (time.perf_counter() - start) if shown else 0.0
        keys = await _keys(app, view, frames, drawn, presses, random.Random(seed))
        runner.pause()
    return ViewFigures(game, rate, tuple(keys))


async def _keys(app: Any, view: Any, frames: list[float],
                drawn: list[tuple[float, int, bool, bool]], presses: int,
                rng: random.Random) -> list[float]:
    out = []
    for i in range(presses):
        key, column = ("d", 3) if i % 2 else ("s", 2)
        target = not (view.numbers if key == "d" else view.runner.latest.in_place)
        before = len(drawn)

        def answered(before: int = before, column: int = column, target: bool = target
                     ) -> float | None:
            hit = next((d[0] for d in drawn[before:] if d[column] == target), None)
            return None if hit is None else next((t for t in frames if t >= hit), None)

        sent, at = await press(app, key, rng, answered, f"the answer to {key}")
        out.append((at - sent) * 1000)
    return out


def measure(seconds: float, presses: int, repeats: int,
            progress: Callable[[str], None] | None = None) -> DPResult:
    """Every figure of the module docstring."""
    from tui_gym.core.mdp.planning import value_sweep
    from tui_gym.games import game_named
    from tui_gym.session.book import figure_named
    from tui_gym.session.book.figure import FigureOptions

    say = progress or (lambda _text: None)
    say("planning: a value-iteration sweep on Taxi")
    taxi = game_named("taxi").plan_model({})
    sweep_s, _ = timed(lambda: value_sweep(taxi.model, np.zeros(500), 1.0), 50)  # type: ignore[union-attr]
    say("planning: Jack's car rental by policy iteration")
    built, _ = timed(lambda: game_named("car-rental").plan_model({}))
    jack, _ = timed(lambda: figure_named("4.2").run(FigureOptions(), lambda *_: None), repeats)
    views = []
    for game in GRID_GAMES:
        say(f"planning: the Plan view on {game}")
        views.append(asyncio.run(_view_once(game, seconds, presses, 0)))
    return DPResult(sweep_s * 1000, jack, built, tuple(views))
