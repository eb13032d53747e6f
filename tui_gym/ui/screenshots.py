"""`tui-gym screenshots`: deterministic SVG screenshots of the app."""

from __future__ import annotations

import asyncio
import os
import tempfile
import time
from collections.abc import Awaitable, Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from unittest import mock

from textual.binding import Binding

from tui_gym.core.files import check_output_path, write_atomically
from tui_gym.core.wrappers import parse_wrapper_spec
from tui_gym.games import GAMES
from tui_gym.games.maps.builtin import builtin_map
from tui_gym.session.session import Session
from tui_gym.ui.widgets.boards import Board

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


async def _press(pilot, *keys: str) -> None:
    """`keys` pressed, and the screen settled."""
    await pilot.press(*keys)
    await pilot.pause()


def _run(session: Session, episodes: int) -> None:
    """`episodes` more trained, timed at the nominal rate."""
    trainer = session.trainer
    trainer.run(episodes=episodes)
    trainer.seconds = trainer.episodes / NOMINAL_EPISODES_PER_SECOND
    trainer._samples.clear()  # the rate over the whole run: the nominal one
    trainer._samples.append((0.0, 0))
    trainer.publish()


async def _redraw(app, pilot) -> None:
    app.train_view.show_snapshot(app.runner.latest, app.runner)
    await pilot.pause()


async def _train_view(app, pilot, episodes: int) -> None:
    _run(app.session, episodes)
    await _press(pilot, "t")
    await _redraw(app, pilot)


def _keys_for(board: Board, action: str) -> list[str]:
    """The keys of the board that take `action`: its own key, or those a board says pick it
    (a dial's); none when no key does."""
    keys_for = getattr(board, "keys_for", None)
    if keys_for is not None:
        return list(keys_for(action))
    for binding in Binding.make_bindings(board.BINDINGS):
        if binding.action == f"act('{action}')":
            return [binding.key]
    return []


async def _play(app, pilot, moves: int = 2) -> None:
    """A few moves as the optimum would make them, by the board's own keys."""
    view = app.play_view
    for _ in range(moves):
        human, board = view.game, view.board
        if human is None or board is None or human.done:
            break
        advice = human.game.oracle.advice(human.env, app.session.env_kwargs)
        action = human.game.action_names[advice.optimal[0] if advice.optimal else 0]
        keys = _keys_for(board, action)
        if not keys:
            break
        await _press(pilot, *keys)


async def _train(app, pilot) -> None:
    """A quarter of the default budget: mid-run, with curves and a heatmap to show."""
    await _train_view(app, pilot, max(1, app.session.hp.episodes // 4))


async def _step_by_step(app, pilot, steps: int = 2) -> None:
    await _train_view(app, pilot, 300)
    for _ in range(steps):  # into the episode, so the board and the panel have history
        await _press(pilot, "n")
        app.runner.wait_idle(10.0)
    await pilot.pause()
    await _redraw(app, pilot)
    app.train_view.step_panel.scroll_visible(animate=False)
    await pilot.pause()


@contextmanager
def _utc() -> Iterator[None]:
    """Times shown in UTC, whatever the machine's zone."""
    try:
        with mock.patch.dict(os.environ, TZ="UTC"):
            time.tzset()
            yield
    finally:
        time.tzset()  # the machine's zone again


async def _compare(app, pilot) -> None:
    """Two learners compared into a scratch history, their runs' times pinned to nominal ones."""
    from tui_gym.core.experiments import RunHistory
    from tui_gym.session.experiments.compare import CompareSpec, run_compare

    session = app.session
    settings, episodes = session.game.demo_compare or ({}, 5_000)
    spec = CompareSpec(game=session.env_id, algorithms=("q-learning", "sarsa"), seeds=10,
                       episodes=episodes, settings=settings, first_seed=session.seed)
    with tempfile.TemporaryDirectory() as folder, _utc():
        db = Path(folder) / "runs.db"
        with RunHistory(db) as history:
            # One batch per algorithm on this thread: the same curves on any number of cores.
            run_compare(spec, history=history, processes=0)
            history._write(lambda conn: conn.execute(
                "UPDATE runs SET started_at = ? + 60 * id, ended_at = ? + 60 * id + 30",
                (NOMINAL_START, NOMINAL_START),
            ))
        app.db = db  # the view reads it when it is first shown
        await _press(pilot, "v")
        view = app.compare_view
        while view is None or len(view.runs) < 2 or app.focused is not view.run_list:
            await pilot.pause()
            view = app.compare_view
        await _press(pilot, "space", "down", "space")  # tick both runs
        view.run_list.highlighted = None
        await pilot.pause()


async def _map_editor(app, pilot) -> None:
    """Trained a while, then a wall painted on the safe way round, and training on."""
    await _train_view(app, pilot, 4_000)
    await _press(pilot, "m")
    await _press(pilot, "right", "right", "right", "2")  # a wall at row 0, col 3
    _run(app.session, 1_000)  # the agent keeps learning on the new map
    await _redraw(app, pilot)
    editor = app.train_view.editor
    if editor is not None:
        app.train_view.scroll_to_widget(editor, top=True, animate=False)
    await pilot.pause()


async def _plan(app, pilot, keys: tuple[str, ...], edit: tuple[str, ...] = ()) -> None:
    """The Plan view: `keys` pressed, each step run to its end, and with `edit` the map
    editor open and those keys pressed in it (planning goes on from the values)."""
    await pilot.press("P")
    view = app.plan_view
    while view is None or view.runner is None:
        await pilot.pause()
        view = app.plan_view

    async def settled() -> None:
        await pilot.pause()
        while view.runner is None or view.runner.latest.running or view.runner._commands:
            await pilot.pause(0.05)
        view._poll()
        await pilot.pause()

    for key in keys:
        await pilot.press(key)
        await settled()
    if edit:
        await _press(pilot, "m")
        await pilot.press(*edit)
        await settled()
        view.focus_default()
        await pilot.pause()


async def _book(app, pilot, figure: str) -> None:
    """The Book view: `figure` run at its defaults, drawn with its verdicts."""
    from tui_gym.ui.book_view import BookView

    await pilot.press("f")
    while not app.query(BookView):
        await pilot.pause()
    view = app.query_one(BookView)
    await pilot.pause()
    index = next(i for i, f in enumerate(view.figures) if f.name == figure)
    await pilot.press(*["down"] * index, "enter")
    while view.running:
        await pilot.pause(0.1)
    await pilot.pause()


async def _traces(app, pilot) -> None:
    """A few steps into an episode, the heatmap turned to the traces they left."""
    await _step_by_step(app, pilot, steps=6)
    await _press(pilot, "E")
    app.train_view.heatmap.scroll_visible(animate=False)
    await pilot.pause()


def _scenarios() -> tuple[Scenario, ...]:
    """Each game played and training, one update step by step, a λ learner's traces, then
    the wrapper panel, a comparison, the keys and 80x24."""
    shots: list[Scenario] = []
    for game in GAMES:
        shots.append(Scenario(f"{game.name}-play.svg", f"{game.title}: play",
                              partial(Session, game.env_id, seed=4), _play))
        shots.append(Scenario(f"{game.name}-train.svg", f"{game.title}: Q-learning mid-run",
                              partial(Session, game.env_id, seed=0), _train))
    first = GAMES[0]
    focused = next((g for g in GAMES if g.layout.has_focus), first)
    shown = next((g for g in GAMES if g.demo_wrappers), first)
    compared = next((g for g in GAMES if g.demo_compare), first)
    choices = tuple(parse_wrapper_spec(text) for text in shown.demo_wrappers)
    mapped = next((g for g in GAMES if "start" in g.map_tools), None)
    if mapped is not None:
        bridge = mapped.with_map({}, builtin_map("bridge").grid_map)
        shots.append(Scenario("map-editor.svg", f"{mapped.title}: a map edited mid-training",
                              partial(Session, mapped.env_id, env_kwargs=bridge, seed=0),
                              _map_editor))
    shots += [
        Scenario("step-by-step.svg", f"{focused.title}: one SARSA update, step by step",
                 partial(Session, focused.env_id, seed=3, algorithm="sarsa"), _step_by_step),
        Scenario("traces.svg", "CliffWalking: Sarsa(λ)'s eligibility traces, six steps in",
                 partial(Session, "cliffwalking", seed=0, algorithm="sarsa-lambda"), _traces),
        Scenario("wrappers.svg", "The wrapper panel in use",
                 partial(Session, shown.env_id, choices=choices, seed=1),
                 lambda app, pilot: _press(pilot, "w")),
        Scenario("compare.svg", f"{compared.title}: Q-learning against SARSA over 10 seeds",
                 partial(Session, compared.env_id, seed=0), _compare),
        Scenario("plan.svg", "FrozenLake: value iteration, then a hole painted while it plans",
                 partial(Session, "frozenlake", seed=0),
                 partial(_plan, keys=("3", "c"), edit=("right", "right", "down", "3"))),
        Scenario("plan-gambler.svg", "Gambler: value iteration, sweep by sweep (Figure 4.3)",
                 partial(Session, "gambler", seed=0), partial(_plan, keys=("3", "c"))),
        Scenario("plan-car-rental.svg", "Jack's car rental: policy iteration (Figure 4.2)",
                 partial(Session, "car-rental", seed=0), partial(_plan, keys=("2", "c"))),
        Scenario("book.svg", "Figure 8.2: Dyna-Q's planning steps on the Dyna maze, checked",
                 partial(Session, "dyna-maze", seed=0), partial(_book, figure="8.2")),
        Scenario("help.svg", "Every key", partial(Session, first.env_id, seed=0),
                 lambda app, pilot: _press(pilot, "question_mark")),
        Scenario("compact-80x24.svg", "The compact layout at 80x24",
                 partial(Session, first.env_id, seed=4), _play, size=(80, 24)),
    ]
    return tuple(shots)


SCENARIOS = _scenarios()


async def _shoot(scenario: Scenario, directory: Path) -> Path:
    from tui_gym.ui.app import TuiGymApp

    app = TuiGymApp(scenario.make_session())
    async with app.run_test(size=scenario.size) as pilot:
        await pilot.pause()
        await scenario.drive(app, pilot)
        await pilot.pause()
        app.title = f"tui-gym — {scenario.title}"
        await pilot.pause()
        svg = app.export_screenshot(title=scenario.title)
    return write_atomically(directory / scenario.filename, svg)


def write_screenshots(directory: str | Path = "screenshots") -> list[Path]:
    """Write every scenario's SVG into `directory` (created if needed); every file's
    path is checked before the first is drawn (`OutputPathError` saying why)."""
    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    for scenario in SCENARIOS:
        check_output_path(folder / scenario.filename)

    async def shoot_all() -> list[Path]:
        return [await _shoot(s, folder) for s in SCENARIOS]

    return asyncio.run(shoot_all())
