"""`TrainingRunner`: a session's trainer on a worker thread, publishing snapshots a UI pulls.

Every control takes effect after the piece of work under way: one call of the compiled
loop at max speed (`CALL_SECONDS`), one agent step at animated speeds.
"""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING, Any

from tui_gym.core.engine.stats import StepEvent, TrainingSnapshot
from tui_gym.core.engine.trainer import Trainer
from tui_gym.session.speeds import DEFAULT_SPEED, SPEEDS, Runner, Speed

if TYPE_CHECKING:
    from tui_gym.session.session import Session


CHUNK_SECONDS = 0.05  # how long one max-speed chunk trains before publishing
# Each call of the compiled loop (which lets go of the interpreter lock) aims at this long:
# coming back, the worker waits for the lock while the UI's thread draws a frame (up to
# `sys.getswitchinterval()`, 5 ms), once a call; a few calls a chunk keep that wait small.
CALL_SECONDS = 0.016
STOP_TIMEOUT = 5.0  # seconds `pause()` and `close()` wait at most for the worker


class TrainingRunner(Runner):
    """Trains `session.trainer` on a background thread, on request."""

    def __init__(self, session: Session, speed: int = DEFAULT_SPEED) -> None:
        self.session = session
        self.speed_index = speed
        self.error: BaseException | None = None
        self.finished = False  # the episode budget was reached
        self._anim_mark = 0.0  # when the last animated step was taken
        # Every flag below changes under `_cond`, and every change notifies it:
        # the worker sleeps on it, between animated steps too.
        self._cond = threading.Condition()
        self._want_run = False
        self._want_one = False
        self._want_step = 0  # steps asked for and not taken yet (a burst of `n` keeps each)
        self._quit = False
        self._working = False  # the worker is inside a piece of work
        self._controls = 0  # counts control changes, to cut an animated pause short
        self._thread = threading.Thread(target=self._loop, name="tui-gym-trainer", daemon=True)
        self._thread.start()

    @property
    def running(self) -> bool:
        return self._want_run

    @property
    def busy(self) -> bool:
        return self._want_run or self._want_one or self._want_step > 0 or self._working

    def _control(self, step: int = 0, **flags: bool | int) -> None:
        """Set the flags named (and ask for `step` more steps), waking the worker."""
        with self._cond:
            for name, value in flags.items():
                setattr(self, f"_{name}", value)
            self._want_step += step
            self._controls += 1
            self._cond.notify_all()

    def update(self) -> None:
        """Nothing to collect: the worker trains the session's own objects."""

    def start(self) -> bool:
        return self._ask(False, want_run=True, want_one=False)

    def pause(self, wait: bool = True, timeout: float = STOP_TIMEOUT) -> bool:
        # The worker finishes the piece of work under way (milliseconds): at once, in practice.
        self._control(want_run=False, want_one=False, want_step=0)
        with self._cond:
            return self._cond.wait_for(lambda: not self._working, timeout)

    def run_one_episode(self) -> bool:
        return self._ask(self._want_run, want_one=True)

    def run_one_step(self) -> bool:
        return self._ask(self._want_run or self._want_one, step=1)

    def _ask(self, busy: bool, step: int = 0, **flags: bool) -> bool:
        """Ask the worker for work unless `busy`; False when the budget is used up."""
        if self.session.trainer.remaining == 0:
            self.finished = True
            return False
        if not busy:
            self.finished = self.finished and not flags.get("want_run", False)
            self.error = None
            self._control(step, **flags)
        return True

    def set_hyperparameters(self, hp: Any) -> None:
        self.session.set_hyperparameters(hp)

    def _speed_changed(self) -> None:
        self._control()  # an animated pause in progress ends: the new pace applies now

    @property
    def latest(self) -> TrainingSnapshot:
        return self.session.trainer.latest

    def wait_idle(self, timeout: float = STOP_TIMEOUT) -> bool:
        with self._cond:
            return self._cond.wait_for(lambda: not self.busy or self._quit, timeout)

    def close(self, wait: bool = True) -> None:
        self._control(quit=True, want_run=False, want_one=False, want_step=0)
        if wait and self._thread is not threading.current_thread():
            self._thread.join(timeout=STOP_TIMEOUT)

    # --- the worker --------------------------------------------------------
    def _loop(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(
                    lambda: self._quit or self._want_run or self._want_one or self._want_step
                )
                if self._quit:
                    return
                self._working = True
                controls = self._controls
            delay = None
            try:
                delay = self._piece()
            except Exception as exc:  # shown to the user by the front end
                self.error = exc
                self._control(want_run=False, want_one=False, want_step=0)
            finally:
                with self._cond:
                    self._working = False
                    self._cond.notify_all()
            if delay:
                self._pause_between_steps(controls, delay)

    def _pause_between_steps(self, controls: int, delay: float) -> None:
        """The pause that makes animated steps readable; any control ends it."""
        with self._cond:
            self._cond.wait_for(lambda: self._controls != controls, delay)

    def _piece(self) -> float | None:
        """One piece of work; returns how long to pause before the next one."""
        speed = self.speed
        trainer = self.session.trainer
        if self._want_step and not self._want_run:
            self._animated_step(trainer)
            with self._cond:
                self._want_step = max(0, self._want_step - 1)
                self._cond.notify_all()
            return None
        if self._want_run:
            if trainer.remaining == 0:
                self.finished = True
                with self._cond:
                    self._want_run = False
                trainer.publish()
                return None
            if speed.animated:
                self._animated_step(trainer)
                return speed.step_delay
            trainer.run(episodes=trainer.remaining, seconds=CHUNK_SECONDS, stop=_Stopped(self),
                        call_seconds=CALL_SECONDS)
            return None
        if not self._want_one:
            return None
        if speed.animated:
            event = self._animated_step(trainer)
            if event.episode_done is None:
                return speed.step_delay
        else:
            trainer.run(episodes=1, stop=_Stopped(self, one=True))
        with self._cond:
            self._want_one = False
            self._cond.notify_all()
        return None

    def _animated_step(self, trainer: Trainer) -> StepEvent:
        """One agent step, explained and remembered with the board's scene for viewers (the
        pause between steps counts as training time: episodes/s tells the pace shown)."""
        now = time.perf_counter()
        if now - self._anim_mark < 2.0:
            trainer.seconds += now - self._anim_mark
        self._anim_mark = now
        _, previous, last = self._shown
        # The scene before this move, while one episode goes on: the board tells a slip.
        before = previous if last is not None and last.episode_done is None else None
        event = trainer.step(explain=True)
        self._shown = (trainer.agent, self.session.game.states.scene(trainer.env, before), event)
        trainer.publish()
        return event


class _Stopped:
    """The trainer's stop flag: set once the runner is no longer asked to do this work."""

    def __init__(self, runner: TrainingRunner, one: bool = False) -> None:
        self._runner = runner
        self._one = one

    def is_set(self) -> bool:
        runner = self._runner
        return runner._quit or not (runner._want_one if self._one else runner._want_run)


__all__ = ["DEFAULT_SPEED", "SPEEDS", "Runner", "Speed", "TrainingRunner"]
