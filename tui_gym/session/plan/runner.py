"""`PlanRunner`: a `Planner` stepped on a thread of its own, for the Plan view."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from tui_gym.core.mdp import FiniteMDP
from tui_gym.core.mdp.planning import Planner, check_method

__all__ = ["DEFAULT_SPEED", "KEPT_SWEEPS", "MAX_SWEEPS", "SPEEDS", "PlanRunner", "PlanSnapshot"]

FloatArray = npt.NDArray[np.float64]
SPEEDS: tuple[tuple[str, float], ...] = (
    ("1/s", 1), ("2/s", 2), ("5/s", 5), ("10/s", 10), ("20/s", 20), ("50/s", 50), ("max", math.inf),
)
DEFAULT_SPEED = 3
MAX_FRAMES = 30  # snapshots a second at the "max" speed
KEPT_SWEEPS = (1, 2, 3)  # the values after these sweeps are kept (the book's first sweeps)
MAX_SWEEPS = 100_000  # a run stops after this many sweeps (values that never settle)


@dataclass(frozen=True)
class PlanSnapshot:
    """The planner as one step left it (arrays are copies, never written again)."""

    version: int
    method: str
    v: FloatArray
    policy: FloatArray
    changed: npt.NDArray[np.bool_]
    sweeps: int
    iterations: int
    delta: float
    gamma: float
    theta: float
    in_place: bool
    speed: int
    running: bool
    done: bool
    step: str = ""  # what the last step did, in words
    note: str = ""  # why a run stopped short, or what a command could not do
    kept: tuple[tuple[int, FloatArray], ...] = field(default=())  # (sweep, values)
    limited_value: float | None = None  # `limited` of the policy (None while a run is on)
    never_ending: int = 0  # with gamma 1, states the policy never ends from (0 while running)


class PlanRunner:
    """A planner behind a command queue, stepped on its own thread (see the module)."""

    def __init__(
        self, model: FiniteMDP, *, method: str = "value-iteration", gamma: float = 1.0,
        theta: float = 1e-6, policy: npt.ArrayLike | None = None, in_place: bool = False,
        speed: int = DEFAULT_SPEED, limited: Callable[[FloatArray], float] | None = None,
        on_command: Callable[[], None] | None = None,
    ) -> None:
        self._limited = limited
        self._on_command = on_command
        self._figures_of: tuple[Any, dict[str, Any]] | None = None
        self._planner = Planner(model, gamma=gamma, theta=theta, policy=policy, in_place=in_place)
        self._method = check_method(method)
        self._speed = speed
        self._running = False
        self._hurry = False  # this run goes at "max", whatever the speed
        self._rerun = False  # a run is on or finished on its own: an edit starts it again
        self._run_limit = 0
        self._kept: list[tuple[int, FloatArray]] = []
        self._step_words = ""
        self._note = ""
        self._version = 0
        self._commands: list[Callable[[], None]] = []
        self._cond = threading.Condition()
        self._closed = False
        self._next_step = 0.0
        self._last_publish = 0.0
        self.latest = self._snapshot()
        self._thread = threading.Thread(target=self._loop, name="plan-runner", daemon=True)
        self._thread.start()

    # --- commands (any thread) ----------------------------------------------
    def _send(self, command: Callable[[], None]) -> None:
        with self._cond:
            self._commands.append(command)
            self._cond.notify()

    def step(self) -> None:
        """One step of the method (a sweep, or an improvement)."""
        self._send(self._one_step)

    def run(self, to_end: bool = False) -> None:
        """Step the method until done or paused: at the chosen speed, or `to_end` at full speed."""
        def start() -> None:
            self._start_run()
            self._hurry = to_end
        self._send(start)

    def pause(self) -> None:
        self._send(self._stop)

    def toggle(self) -> None:
        """Run when paused, pause when running."""
        self._send(lambda: self._stop() if self._running else self._start_run())

    def improve(self) -> None:
        """One policy improvement on the current values."""
        def improve() -> None:
            step = self._planner.improvement()
            count = int(step.changed.sum())
            self._step_words = ("policy stable: no state changed its action" if step.stable
                                else f"improvement: {count} state{'s' * (count != 1)} changed")
        self._send(improve)

    def set_method(self, method: str) -> None:
        check_method(method)
        self._send(lambda: setattr(self, "_method", method))

    def set_speed(self, speed: int) -> None:
        speed = max(0, min(len(SPEEDS) - 1, speed))
        self._send(lambda: setattr(self, "_speed", speed))

    def set_gamma(self, gamma: float) -> None:
        self._send(lambda: self._settled(self._planner.set_gamma, gamma))

    def set_theta(self, theta: float) -> None:
        self._send(lambda: self._settled(self._planner.set_theta, theta))

    def set_in_place(self, in_place: bool) -> None:
        self._send(lambda: setattr(self._planner, "in_place", bool(in_place)))

    def restart(self, policy: npt.ArrayLike | Callable[[], npt.ArrayLike] | None) -> None:
        """Start over from `policy` (None: random; a function: what it returns, called on
        the runner's thread) with zero values; a run stops."""
        def restart() -> None:
            self._planner.restart(policy() if callable(policy) else policy)
            self._stop()
            self._kept.clear()
            self._step_words = "started over"
        self._send(restart)

    def set_model(self, model: FiniteMDP,
                  limited: Callable[[FloatArray], float] | None = None) -> None:
        """Plan on an edited world (same states: from the current values); a run goes on."""
        def change() -> None:
            self._planner.set_model(model)
            self._limited, self._figures_of = limited, None
            self._step_words = "the world changed"
            if self._rerun:
                self._start_run()
        self._send(change)

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify()
        self._thread.join(timeout=5)

    # --- the thread -----------------------------------------------------------
    def _settled(self, setter: Callable[[float], None], value: float) -> None:
        setter(value)
        self._step_words = ""

    def _stop(self) -> None:
        self._running = self._rerun = False

    def _start_run(self) -> None:
        self._hurry = False
        if self._planner.done(self._method):
            self._step_words = "done already: change a setting or start over"
            return
        self._running = self._rerun = True
        self._run_limit = self._planner.sweeps + MAX_SWEEPS
        self._next_step = time.monotonic()

    def _one_step(self) -> None:
        planner = self._planner
        before = planner.sweeps
        words = planner.step(self._method)
        if not words:
            self._step_words = "done: nothing left to do"
            return
        if planner.sweeps != before and planner.sweeps in KEPT_SWEEPS:
            self._kept.append((planner.sweeps, planner.v.copy()))
        delta = planner.delta
        if words.endswith("sweep") and math.isfinite(delta):
            words += f": largest change {delta:.4g}"
        elif words == "improvement":
            count = int(planner.changed.sum())
            words += f": {count} state{'s' * (count != 1)} changed"
        self._step_words = words

    def _loop(self) -> None:
        while True:
            with self._cond:
                while not self._commands and not self._closed:
                    if self._running:
                        wait = self._next_step - time.monotonic()
                        if wait <= 0:
                            break
                        self._cond.wait(wait)
                    else:
                        self._cond.wait()
                if self._closed:
                    return
                commands, self._commands = self._commands, []
            for command in commands:
                try:
                    command()
                except ValueError as error:  # a setting the planner refused
                    self._note = str(error)
            stepped = False
            if self._running and time.monotonic() >= self._next_step:
                self._run_step()
                stepped = True
            if commands or not stepped or self._publish_due():
                self._last_publish = time.monotonic()
                self._version += 1
                self.latest = self._snapshot()
            if commands and self._on_command is not None:
                self._on_command()

    def _run_step(self) -> None:
        planner = self._planner
        self._one_step()
        self._note = ""
        rate = math.inf if self._hurry else SPEEDS[self._speed][1]
        self._next_step = time.monotonic() + (0.0 if math.isinf(rate) else 1.0 / rate)
        if planner.done(self._method):
            self._running = False
        elif planner.sweeps >= self._run_limit or not np.isfinite(planner.v).all():
            self._stop()
            self._note = (f"stopped after {planner.sweeps:,} sweeps: the values do not settle "
                          "(with γ = 1 a policy that never ends has no finite value)")

    def _publish_due(self) -> bool:
        """Whether a run's step is shown: every one at the animated speeds, at most
        `MAX_FRAMES` a second at "max", and the last one always."""
        if not self._running:
            return True
        if not (self._hurry or math.isinf(SPEEDS[self._speed][1])):
            return True
        return time.monotonic() - self._last_publish >= 1.0 / MAX_FRAMES

    def _snapshot(self) -> PlanSnapshot:
        planner = self._planner
        arrays = [planner.v.copy(), planner.policy.copy(), planner.changed.copy()]
        for array in arrays:
            array.setflags(write=False)
        return PlanSnapshot(
            version=self._version, method=self._method, v=arrays[0], policy=arrays[1],
            changed=arrays[2], sweeps=planner.sweeps, iterations=planner.iterations,
            delta=planner.delta, gamma=planner.gamma, theta=planner.theta,
            in_place=planner.in_place, speed=self._speed, running=self._running,
            done=planner.done(self._method), step=self._step_words, note=self._note,
            kept=tuple(self._kept), **({} if self._running else self._policy_figures(arrays[1])),
        )

    def _policy_figures(self, policy: FloatArray) -> dict[str, Any]:
        """The policy's `limited` value, and with gamma 1 the states it never ends from
        (computed again only for a new policy)."""
        key = (policy.tobytes(), self._planner.gamma)
        if self._figures_of is None or self._figures_of[0] != key:
            figures: dict[str, Any] = {}
            if self._limited is not None:
                figures["limited_value"] = self._limited(policy)
            if self._planner.gamma == 1.0:
                figures["never_ending"] = int(self._planner.never_ending().sum())
            self._figures_of = (key, figures)
        return self._figures_of[1]
