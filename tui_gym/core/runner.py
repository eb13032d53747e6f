"""Background training: runs a session's trainer on a worker thread.

`TrainingRunner` owns one daemon thread. Front ends call `start()`,
`pause()`, `run_one_episode()` and `set_speed()`; the thread trains in short
chunks and publishes snapshots (the trainer's `latest`), which a UI pulls on a
timer. Nothing here calls back into a front end, so a slow viewer can never
slow training down, and a fast trainer never blocks the viewer.

Speeds run from *animated* (one agent step at a time, slow enough to follow,
with the last move kept in `last_event` for a board to draw) to *max* (whole
chunks of episodes, no pauses).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from tui_gym.core.training import StepEvent, TrainingSnapshot

if TYPE_CHECKING:
    from tui_gym.core.session import Session


@dataclass(frozen=True)
class Speed:
    """One training speed: a step delay for animated speeds, or whole chunks."""

    name: str
    step_delay: float | None  # seconds between agent steps; None = chunks of episodes

    @property
    def animated(self) -> bool:
        return self.step_delay is not None


SPEEDS: tuple[Speed, ...] = (
    Speed("animated (slow)", 0.35),
    Speed("animated", 0.12),
    Speed("animated (fast)", 0.03),
    Speed("max", None),
)
DEFAULT_SPEED = len(SPEEDS) - 1
CHUNK_SECONDS = 0.05  # how long one max-speed chunk trains before checking for a pause


class TrainingRunner:
    """Trains `session.trainer` on a background thread, on request."""

    def __init__(self, session: Session, speed: int = DEFAULT_SPEED) -> None:
        self.session = session
        self.speed_index = speed
        self.last_event: StepEvent | None = None
        self.last_scene: dict | None = None  # the board after the last animated step
        self.error: BaseException | None = None
        self.finished = False  # the episode budget was reached
        self._anim_mark = 0.0  # when the last animated step was taken
        self._want_run = threading.Event()
        self._idle = threading.Event()
        self._idle.set()
        self._one_episode = threading.Event()
        self._quit = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._loop, name="tui-gym-trainer", daemon=True)
        self._thread.start()

    # --- controls (any thread) ---------------------------------------------
    @property
    def speed(self) -> Speed:
        return SPEEDS[self.speed_index]

    @property
    def running(self) -> bool:
        """True while training is switched on (it may be between chunks)."""
        return self._want_run.is_set()

    def start(self) -> bool:
        """Train until paused or the budget is reached; False when the budget is used up."""
        if self.session.trainer.remaining == 0:
            self.finished = True
            return False
        self.finished = False
        self.error = None
        self._want_run.set()
        return True

    def pause(self, wait: bool = True, timeout: float = 5.0) -> None:
        """Stop training after the current chunk; with `wait`, return once it has stopped."""
        self._want_run.clear()
        self._one_episode.clear()
        if wait:
            self._idle.wait(timeout)

    def toggle(self) -> bool:
        """Start when paused, pause when running; returns whether it now runs."""
        if self.running:
            self.pause(wait=False)
            return False
        return self.start()

    def run_one_episode(self) -> None:
        """Play one training episode on the worker (ignored while running)."""
        if not self.running:
            self.error = None
            self._one_episode.set()

    def set_speed(self, index: int) -> Speed:
        self.speed_index = max(0, min(len(SPEEDS) - 1, index))
        return self.speed

    def faster(self) -> Speed:
        return self.set_speed(self.speed_index + 1)

    def slower(self) -> Speed:
        return self.set_speed(self.speed_index - 1)

    @property
    def latest(self) -> TrainingSnapshot:
        return self.session.trainer.latest

    def wait_idle(self, timeout: float = 5.0) -> bool:
        """Wait until the worker is not inside a chunk."""
        return self._idle.wait(timeout)

    def close(self) -> None:
        """Stop the worker thread for good."""
        self._quit.set()
        self._want_run.clear()
        self._one_episode.set()  # wake it
        self._thread.join(timeout=5.0)

    # --- the worker --------------------------------------------------------
    def _loop(self) -> None:
        while not self._quit.is_set():
            if not (self._want_run.is_set() or self._one_episode.is_set()):
                self._idle.set()
                # Sleep until asked to work (short waits keep quit responsive).
                self._want_run.wait(0.05) or self._one_episode.wait(0.05)
                continue
            self._idle.clear()
            if self._quit.is_set():
                break
            try:
                if self._one_episode.is_set() and not self._want_run.is_set():
                    self._episode_once()
                    self._one_episode.clear()
                else:
                    self._chunk()
            except Exception as exc:  # shown to the user by the front end
                self.error = exc
                self._want_run.clear()
                self._one_episode.clear()
        self._idle.set()

    def _episode_once(self) -> None:
        speed = self.speed
        trainer = self.session.trainer_for(speed.animated)
        if speed.animated:
            while not self._quit.is_set():
                self._animated_step(trainer)
                if self.last_event.episode_done is not None:
                    return
                time.sleep(speed.step_delay or 0.0)
        else:
            trainer.run(episodes=1)

    def _animated_step(self, trainer) -> None:
        """One agent step, remembered (with the board's scene) for viewers.

        The time between animated steps (the pause that makes them readable)
        counts as training time, so episodes/s tells the pace being shown.
        """
        now = time.perf_counter()
        if now - self._anim_mark < 2.0:
            trainer.seconds += now - self._anim_mark
        self._anim_mark = now
        event = trainer.step()
        self.last_event = event
        self.last_scene = self.session.profile.scene(trainer.env)
        trainer.publish()

    def _chunk(self) -> None:
        speed = self.speed
        trainer = self.session.trainer_for(speed.animated)
        if trainer.remaining == 0:
            self.finished = True
            self._want_run.clear()
            trainer.publish()
            return
        if speed.animated:
            self._animated_step(trainer)
            time.sleep(speed.step_delay or 0.0)
            return
        trainer.run(
            episodes=trainer.remaining, seconds=CHUNK_SECONDS, stop=_Inverted(self._want_run)
        )


class _Inverted:
    """A stop flag that is set when the wrapped 'keep running' event is cleared."""

    def __init__(self, event: threading.Event) -> None:
        self._event = event

    def is_set(self) -> bool:
        return not self._event.is_set()


RUNNERS = ("thread", "process")


def make_runner(session: Session, kind: str = "thread", speed: int = DEFAULT_SPEED):
    """A runner of the given kind: "thread" (this process) or "process" (a child process)."""
    if kind == "thread":
        return TrainingRunner(session, speed)
    if kind == "process":
        from tui_gym.core.process_runner import ProcessRunner

        return ProcessRunner(session, speed)
    raise ValueError(f"runner must be one of {', '.join(RUNNERS)}, got {kind!r}")
