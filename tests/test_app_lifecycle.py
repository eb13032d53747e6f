"""The app stays up, answers at once and ends well: as a person runs it, for real.

Pilot tests run the real app with its real timers (the garbage collector's
periods shortened so every periodic job fires within a second or two); the
pseudo-terminal tests launch the installed `tui-gym` console script (or the
same `run_standalone` path) as a person would, and read what reaches the
terminal. Every wait polls a condition with a deadline.
"""

from __future__ import annotations

import inspect
import os
import re
import signal
import sys
import textwrap
import time
from pathlib import Path

import pytest
from textual._callback import count_parameters
from textual.timer import Timer

from tui_gym.algorithms import QLearning
from tui_gym.games import game_for
from tui_gym.session.session import Session, default_settings
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.confirm_screen import ConfirmScreen
from tui_gym.ui.train_view import TrainView

from .terminal import Terminal, console_script, descendants, ended
from .waiting import press_busy, quit_busy, send_key, wait_for, wait_until

DEADLINE = 20.0  # seconds; generous for a loaded machine, never reached when things work
LEAVE_ALT_SCREEN = b"\x1b[?1049l"
MOUSE_OFF = b"\x1b[?1000l"
ANSI = re.compile(r"\x1b(\[[0-9;?<>=]*[ -/]*[@-~]|[@-_])")


def process_state(pid: int) -> str:
    """A process's state letter from /proc (`T`: stopped)."""
    return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]


def all_timers(app: TuiGymApp) -> list[Timer]:
    nodes = [app, *app.screen_stack, *app.screen.walk_children()]
    return [timer for node in nodes for timer in list(node._timers)]


# --- the real timers -----------------------------------------------------------
async def test_the_real_app_outlives_the_first_firing_of_every_periodic_job() -> None:
    import gc

    hp = QLearning.hyperparameters(episodes=10_000_000)
    # As `tui-gym` runs: training in a child process, so the event loop has its core.
    app = TuiGymApp(Session("blackjack", seed=0, hp=hp), runner="process", tune_gc=True,
                    gc_seconds=(0.05, 0.3))
    try:
        async with app.run_test(size=(80, 24)) as pilot:
            began = time.monotonic()
            await pilot.press("t")
            send_key(pilot, "space")  # training from here: no wait for an idle process
            await wait_until(pilot, lambda: app.runner.running, "training")
            timers = all_timers(app)
            assert {"young-gc", "full-gc"} <= {t.name for t in timers}
            for timer in timers:  # a built-in here is what crashed the app at 20 s
                if timer._callback is not None:
                    count_parameters(timer._callback)
            for command in app.get_system_commands(app.screen):  # the palette's, likewise
                count_parameters(command.callback)
            longest = max(t._interval for t in timers)
            assert longest <= 1.0, "every periodic job must fire within the test"
            pacer = app.gc_pacer
            assert pacer is not None
            await wait_until(
                pilot,
                lambda: pacer.full_collections >= 2 and time.monotonic() - began > longest * 1.5
                and app.runner.latest.episodes > 0,  # the child loads the compiled learners first
                "every periodic job to have fired, and training",
            )
            assert pacer.young_collections > pacer.full_collections
            assert app.is_running and app.return_code is None
            assert app.runner.running and app.runner.latest.episodes > 0
            await quit_busy(pilot)
        assert app.return_code == 0
    finally:
        gc.enable()
        gc.unfreeze()


# --- one frame, whatever the speed -------------------------------------------------
def animated_gridworld(runner: str) -> TuiGymApp:
    hp = default_settings(game_for("gridworld"), "q-learning").replace(episodes=100_000)
    return TuiGymApp(Session("gridworld", seed=0, hp=hp), runner=runner)


def record_runner_calls(app: TuiGymApp) -> list[tuple[str, dict]]:
    """Every control call the app makes on its runner: its name and its arguments, the
    defaults filled in."""
    calls: list[tuple[str, dict]] = []
    runner = app.runner
    for name in ("start", "pause", "run_one_episode", "set_speed", "close", "update",
                 "wait_idle"):
        method = getattr(runner, name)

        def recorded(*args, _name=name, _method=method, **kwargs):
            bound = inspect.signature(_method).bind(*args, **kwargs)
            bound.apply_defaults()
            calls.append((_name, dict(bound.arguments)))
            return _method(*args, **kwargs)

        setattr(runner, name, recorded)
    return calls


def waits(calls: list[tuple[str, dict]]) -> list[tuple[str, dict]]:
    """The calls that wait on the training worker: a pause or a close with `wait`, a
    `wait_idle` with a timeout. The app makes none (the freezes were 5 s with the thread
    runner and 10 s with the process runner)."""
    return [(name, arguments) for name, arguments in calls
            if arguments.get("wait") is True or (name == "wait_idle" and arguments["timeout"])]


@pytest.mark.parametrize("runner", ["thread", "process"])
async def test_pause_reset_switch_and_quit_take_effect_at_once_mid_episode(runner: str) -> None:
    app = animated_gridworld(runner)
    async with app.run_test(size=(80, 24)) as pilot:
        calls = record_runner_calls(app)
        await pilot.press("t", "minus", "minus", "minus")  # animated (slow)
        assert app.runner.speed.name == "animated (slow)"
        view = app.query_one(TrainView)
        # `.` animates one episode on the board, with a step count.
        await pilot.press("full_stop")
        await wait_for(pilot, lambda: app.runner.last_event is not None
                       and app.runner.last_event.step >= 2, "two animated steps")
        await wait_for(pilot, lambda: "step 2" in str(view._caption.content), "the step count")
        assert view._board_box.has_class("-shown")
        # The switch lands at once though the episode has many slow steps to go.
        gridworld = app.session
        await pilot.press("b")
        await wait_for(pilot, lambda: app.session.game.name == "blackjack", "Blackjack")
        assert gridworld.trainer.episodes == 0, "the switch waited for the episode to end"
        # space then runs at once: no "running" at 0 episodes for seconds. A key that
        # starts training goes without the pilot's wait for an idle process (it would
        # train on meanwhile); one that stops it is pressed as usual.
        await pilot.press("plus", "plus")  # animated (fast)
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.latest.episodes >= 1, "the first hand")
        await pilot.press("space")
        assert not app.runner.running
        await pilot.press("g")
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.last_event is not None, "an animated step")
        await pilot.press("x")
        if isinstance(app.screen, ConfirmScreen):  # an episode ended first: it asks
            await pilot.press("y")
        assert not app.runner.running and app.runner.latest.episodes == 0
        await wait_for(pilot, lambda: not app.runner.busy, "the old agent to come back")
        assert app.session.trainer.episodes == 0, "the reset lost to the old agent"
        send_key(pilot, "space")
        await wait_until(pilot, lambda: app.runner.running, "training")
        await quit_busy(pilot)
    assert app.return_code == 0
    assert {"pause", "start", "close"} <= {name for name, _ in calls}
    assert waits(calls) == []


# --- the training process ----------------------------------------------------------
async def test_a_new_game_is_built_while_the_app_answers(monkeypatch) -> None:
    """A game whose model takes long to build: the app keeps handling keys, says it is
    loading, and switches once the build is done, unless another game was asked for
    meanwhile; a build that fails is said in one line and changes nothing."""
    import threading

    from tui_gym.ui import app as app_module

    release = threading.Event()
    built: list[str] = []

    class SlowSession(Session):
        def __init__(self, env_id: str, **kwargs) -> None:
            if env_id.startswith("Taxi"):
                raise ValueError("taxi\x1b[2J is out of order")
            assert release.wait(DEADLINE), "the test never released the build"
            super().__init__(env_id, **kwargs)
            built.append(env_id)

    monkeypatch.setattr(app_module, "Session", SlowSession)
    monkeypatch.setattr(app_module, "LOADING_NOTICE", 0.01)
    app = TuiGymApp(Session("gridworld", seed=0))
    said: list[str] = []  # every notice, also those gone from the screen by now
    notify = app.notify
    monkeypatch.setattr(app, "notify", lambda message, **kw: (said.append(message),
                                                              notify(message, **kw)))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("b", "t")  # Blackjack's build waits; the view switch does not
        assert app.current_view == "train" and app.session.game.name == "gridworld"
        await wait_for(pilot, lambda: "Loading Blackjack…" in said, "the loading notice")
        release.set()
        await wait_for(pilot, lambda: app.session.game.name == "blackjack", "Blackjack")

        release.clear()
        await pilot.press("F", "g")  # FrozenLake asked for, then GridWorld (kept)
        await wait_for(pilot, lambda: app.session.game.name == "gridworld", "GridWorld")
        release.set()
        await wait_for(pilot, lambda: any("FrozenLake" in e for e in built), "FrozenLake")
        await pilot.pause()
        assert app.session.game.name == "gridworld", "a build finished late took the screen"

        await pilot.press("T")  # Taxi's build fails
        await wait_for(pilot, lambda: any("could not start" in m for m in said), "the error")
        message = next(m for m in said if "could not start" in m)
        assert "\x1b" not in message and "out of order" in message
        assert app.session.game.name == "gridworld"


async def test_a_stopped_or_killed_training_process_never_stops_the_app() -> None:
    hp = QLearning.hyperparameters(episodes=10_000_000)
    app = TuiGymApp(Session("blackjack", seed=0, hp=hp), runner="process")
    notices: list[str] = []
    app.notify = lambda message, **kw: notices.append(message)  # type: ignore[method-assign]
    async with app.run_test(size=(80, 24)) as pilot:
        runner = app.runner
        # While training runs, keys go without the pilot's wait for an idle process.
        await pilot.press("t")
        send_key(pilot, "space")
        await wait_until(pilot, lambda: runner.latest.episodes > 1000, "some training")
        # A stopped child: the reset lands at once, and wins over the agent it hands back.
        stopped = runner.child_pid
        os.kill(stopped, signal.SIGSTOP)
        try:
            calls = record_runner_calls(app)
            await press_busy(pilot, "x", "y")  # it has trained: it asks
            assert runner.latest.episodes == 0
            assert waits(calls) == []
            # Nothing waited until the child counted as hung: the same child, still stopped.
            assert runner.child_pid == stopped and process_state(stopped) == "T"
        finally:
            os.kill(stopped, signal.SIGCONT)
        await wait_for(pilot, lambda: not runner.busy, "the old agent to come back")
        assert app.session.trainer.episodes == 0 and app.session.agent.episode == 0
        assert not app.session.agent.q.any(), "the old table must not come back"
        # A killed child: reaped, replaced, and the agent handed back last is kept.
        send_key(pilot, "space")
        await wait_until(pilot, lambda: runner.latest.episodes > 1000, "some training")
        send_key(pilot, "space")
        await wait_for(pilot, lambda: not runner.running and not runner.busy,
                       "the agent to come back")
        kept = app.session.trainer.episodes
        send_key(pilot, "space")
        await wait_until(pilot, lambda: runner.latest.episodes > kept, "training again")
        dead = runner.child_pid
        os.kill(dead, signal.SIGKILL)
        await wait_for(pilot, lambda: any("killed" in n for n in notices), "the notice")
        assert not runner.running
        assert not Path(f"/proc/{dead}").exists(), "the dead child must be reaped, not a zombie"
        assert app.session.trainer.episodes == kept, "the last handed-over agent is kept"
        await pilot.press("minus", "plus", "full_stop")  # these raised BrokenPipeError,
        send_key(pilot, "space")  # and this
        await wait_until(pilot, lambda: runner.latest.episodes > kept + 1000, "training again")
        assert runner.child_pid != dead
        await quit_busy(pilot)
    assert app.return_code == 0


# --- the console script in a pseudo-terminal -----------------------------------------
@pytest.fixture
def log_dir(tmp_path: Path) -> Path:
    return tmp_path / "logs"


def test_the_console_script_trains_at_max_past_every_periodic_job_and_quits(
    log_dir, tmp_path
) -> None:
    agent = tmp_path / "long.tgym"  # a budget that lasts: training stays at max throughout
    Session("blackjack", seed=1, hp=QLearning.hyperparameters(episodes=100_000_000)).save(agent)
    term = Terminal([console_script(), "--load", str(agent)],
                    {"TUI_GYM_GC_SECONDS": "0.05,0.2", "TUI_GYM_LOG_DIR": str(log_dir)})
    try:
        term.wait_for_text("tui-gym")  # the header: the app is up
        term.type("t")
        term.wait_for_text("Hyperparameters")
        term.type(" ")
        term.wait_for_text("running")
        term.after(0.5)  # two full collections and more, at max speed
        for key in "-+.":
            term.type(key)
        term.type(" ")
        term.wait_for_text("paused")
        term.type("q")
        code = term.exit_code()
    finally:
        term.close()
    text = term.text
    assert code == 0, text[-2000:]
    assert "Traceback" not in text
    assert LEAVE_ALT_SCREEN in term.output
    assert not log_dir.exists(), "no crash log for a run that went well"


def test_an_unexpected_error_ends_the_app_with_one_line_and_a_crash_log(log_dir, tmp_path) -> None:
    script = tmp_path / "broken_app.py"  # a file: Textual looks for the app class's source
    script.write_text(textwrap.dedent("""
        from pathlib import Path

        import tui_gym.ui.app
        from tui_gym.session.session import Session
        from tui_gym.ui.app import TuiGymApp, run_standalone

        class Broken(TuiGymApp):
            CSS_PATH = Path(tui_gym.ui.app.__file__).with_name("app.tcss")

            def _tick(self):
                raise RuntimeError("the tick went wrong")

        raise SystemExit(run_standalone(Broken(Session(), runner="thread", tune_gc=True)))
    """))
    term = Terminal([sys.executable, str(script)], {"TUI_GYM_LOG_DIR": str(log_dir)})
    try:
        code = term.exit_code()
    finally:
        term.close()
    assert code == 1
    output = bytes(term.output)
    assert LEAVE_ALT_SCREEN in output
    after = ANSI.sub("", output.rsplit(LEAVE_ALT_SCREEN, 1)[1].decode("utf-8", "replace"))
    lines = [line for line in after.replace("\r", "").split("\n") if line.strip()]
    assert len(lines) == 1, after
    assert "Traceback" not in term.text
    logs = list(log_dir.glob("crash-*.log"))
    assert len(logs) == 1 and str(logs[0]) in lines[0]
    assert "RuntimeError: the tick went wrong" in lines[0]
    logged = logs[0].read_text()
    assert "Traceback" in logged and "the tick went wrong" in logged and "_tick" in logged


def test_sigterm_restores_the_terminal_and_ends_the_training_process(log_dir) -> None:
    term = Terminal([console_script(), "--env", "gridworld"], {"TUI_GYM_LOG_DIR": str(log_dir)})
    try:
        term.wait_for_text("tui-gym")  # the header: the app is up
        term.type("t")
        term.wait_for_text("Hyperparameters")
        # Animated, so training still runs when the signal comes (at max the default
        # budget is done within a frame on an idle machine).
        term.type("-")
        term.type(" ")
        term.wait_for_text("running")
        children = descendants(term.process.pid)
        term.process.send_signal(signal.SIGTERM)
        code = term.exit_code()
    finally:
        term.close()
    assert code == 128 + signal.SIGTERM
    tail = bytes(term.output[-400:])
    assert LEAVE_ALT_SCREEN in tail and MOUSE_OFF in tail, tail
    assert "Traceback" not in term.text
    # The training process (and multiprocessing's resource tracker) end with the app.
    deadline = time.monotonic() + DEADLINE
    while not all(ended(pid) for pid in children):
        assert time.monotonic() < deadline, "a child process outlived the app"
        time.sleep(0.02)  # polling a condition with a deadline
