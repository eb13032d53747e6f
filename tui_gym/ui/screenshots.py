"""`tui-gym screenshots`: deterministic SVG screenshots of the app.

Each scenario builds a seeded Session, drives the real app headless with
Textual's pilot (keys a person would press), trains synchronously where a
training picture is wanted (so the picture does not depend on thread timing),
and saves an SVG. Timing figures (episodes/s, seconds) are pinned to nominal
values in these pictures only, so the files change only when the app does.
"""

from __future__ import annotations

import asyncio
import os
import sqlite3
import tempfile
import time
from collections.abc import Awaitable, Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tui_gym.algorithms import QLearning
from tui_gym.core.session import Session
from tui_gym.core.wrappers import WrapperChoice

SIZE = (120, 40)
NOMINAL_EPISODES_PER_SECOND = 50_000.0
NOMINAL_START = 1_790_000_000.0  # when the pictured runs started (2026-09-21, UTC)


@dataclass(frozen=True)
class Scenario:
    """One picture: a file name, a session to open and what to do before the shot."""

    filename: str
    title: str
    make_session: Callable[[], Session]
    drive: Callable[..., Awaitable[None]]
    size: tuple[int, int] = SIZE


def _pin_timing(session: Session) -> None:
    trainer = session.trainer
    trainer.seconds = trainer.episodes / NOMINAL_EPISODES_PER_SECOND
    trainer._rate = NOMINAL_EPISODES_PER_SECOND
    trainer._rate_mark = (trainer.seconds, trainer.episodes)
    trainer.publish()


async def _train_view(app, pilot, episodes: int) -> None:
    app.session.trainer.run(episodes=episodes)
    _pin_timing(app.session)
    await pilot.press("t")
    await pilot.pause()
    app.train_view.show_snapshot(app.runner.latest, app.runner)
    await pilot.pause()


async def _blackjack_play(app, pilot) -> None:
    await pilot.press("h")
    await pilot.pause()


async def _gridworld_play(app, pilot) -> None:
    for key in ("right", "up"):
        await pilot.press(key)
    await pilot.pause()


async def _blackjack_train(app, pilot) -> None:
    await _train_view(app, pilot, 60_000)


async def _gridworld_train(app, pilot) -> None:
    await _train_view(app, pilot, 2_000)


async def _step_by_step(app, pilot) -> None:
    await _train_view(app, pilot, 300)
    for _ in range(2):  # a step into the episode, so the board and the panel have history
        await pilot.press("n")
        await pilot.pause()
        app.runner.wait_idle(10.0)
    await pilot.pause()
    app.train_view.show_snapshot(app.runner.latest, app.runner)
    await pilot.pause()
    app.train_view.step_panel.scroll_visible(animate=False)
    await pilot.pause()


def _record_comparison(db: Path, spec: Any) -> None:
    """Record a comparison into `db`, its runs' times pinned to nominal ones."""
    from tui_gym.core.experiments import RunHistory
    from tui_gym.core.experiments.compare import run_compare

    with RunHistory(db) as history:
        # One batch per algorithm on this thread: the same curves on any number of cores.
        run_compare(spec, history=history, processes=0)
    conn = sqlite3.connect(db)
    with conn:
        conn.execute(
            "UPDATE runs SET started_at = ? + 60 * id, ended_at = ? + 60 * id + 30",
            (NOMINAL_START, NOMINAL_START),
        )
    conn.close()


@contextmanager
def _utc() -> Iterator[None]:
    """Times shown in UTC, whatever the machine's zone."""
    saved = os.environ.get("TZ")
    os.environ["TZ"] = "UTC"
    time.tzset()
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop("TZ", None)
        else:
            os.environ["TZ"] = saved
        time.tzset()


async def _compare(app, pilot) -> None:
    from tui_gym.core.experiments.compare import CompareSpec

    session = app.session
    spec = CompareSpec(game=session.env_id, algorithms=("q-learning", "sarsa"), seeds=10,
                       episodes=5_000, first_seed=session.seed)
    with tempfile.TemporaryDirectory() as folder, _utc():
        db = Path(folder) / "runs.db"
        _record_comparison(db, spec)
        view = app.compare_view
        view.db = db
        await pilot.press("v")
        await pilot.pause()
        await pilot.press("space", "down", "space")  # tick both runs
        await pilot.pause()
        view.run_list.highlighted = None
        await pilot.pause()


async def _wrappers(app, pilot) -> None:
    await pilot.press("w")
    await pilot.pause()


async def _help(app, pilot) -> None:
    await pilot.press("question_mark")
    await pilot.pause()


SCENARIOS: tuple[Scenario, ...] = (
    Scenario("blackjack-play.svg", "Blackjack: play a hand",
             lambda: Session("blackjack", seed=4), _blackjack_play),
    Scenario("gridworld-play.svg", "GridWorld: walk to the target",
             lambda: Session("gridworld", seed=2), _gridworld_play),
    Scenario("blackjack-train.svg", "Blackjack: Q-learning mid-run",
             lambda: Session("blackjack", seed=0), _blackjack_train),
    Scenario("gridworld-train.svg", "GridWorld: Q-learning mid-run",
             lambda: Session("gridworld", hp=QLearning.hyperparameters(
                 discount=0.95, learning_rate=0.1, episodes=20_000), seed=0),
             _gridworld_train),
    Scenario("step-by-step.svg", "GridWorld: one SARSA update, step by step",
             lambda: Session("gridworld", seed=3, algorithm="sarsa"), _step_by_step),
    Scenario("wrappers.svg", "The wrapper panel in use",
             lambda: Session("gridworld", choices=(
                 WrapperChoice.make("TimeLimit", max_episode_steps=50),
                 WrapperChoice.make("StepPenalty", penalty=0.01),
                 WrapperChoice.make("DistanceShaping"),
             ), seed=1), _wrappers),
    Scenario("compare.svg", "Q-learning against SARSA over 10 seeds",
             lambda: Session("blackjack", seed=0), _compare),
    Scenario("help.svg", "Every key", lambda: Session("blackjack", seed=0), _help),
    Scenario("compact-80x24.svg", "The compact layout at 80x24",
             lambda: Session("blackjack", seed=4), _blackjack_play, size=(80, 24)),
)


async def _shoot(scenario: Scenario, directory: Path) -> Path:
    from tui_gym.ui.app import TuiGymApp

    app = TuiGymApp(scenario.make_session())
    async with app.run_test(size=scenario.size) as pilot:
        await pilot.pause()
        await scenario.drive(app, pilot)
        await pilot.pause()
        app.title = f"tui-gym — {scenario.title}"
        await pilot.pause()
        path = directory / scenario.filename
        svg = app.export_screenshot(title=scenario.title)
    tmp = path.with_suffix(".svg.tmp")
    tmp.write_text(svg, encoding="utf-8")
    tmp.replace(path)
    return path


def write_screenshots(directory: str | Path = "screenshots") -> list[Path]:
    """Write every scenario's SVG into `directory` (created if needed)."""
    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)

    async def shoot_all() -> list[Path]:
        return [await _shoot(s, folder) for s in SCENARIOS]

    return asyncio.run(shoot_all())
