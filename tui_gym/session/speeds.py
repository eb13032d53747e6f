"""Training speeds, from *animated* (one step at a time, the last move kept for a board) to
*max* (whole chunks of episodes), and `Runner`, the base of every runner (thread, process).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tui_gym.core.engine.stats import StepEvent, TrainingSnapshot
    from tui_gym.session.session import Session

__all__ = ["DEFAULT_SPEED", "SPEEDS", "Runner", "Speed"]


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


class Runner(ABC):
    """What a front end asks of a runner: controls, the latest snapshot, the last move."""

    session: Session
    error: BaseException | None
    finished: bool
    speed_index: int
    _shown: tuple[Any, dict[str, Any] | None, StepEvent | None] = (None, None, None)

    @property
    @abstractmethod
    def running(self) -> bool:
        """True while training is switched on (it may be between pieces of work)."""

    @property
    @abstractmethod
    def busy(self) -> bool:
        """True while training is on, an episode or step is asked for, or work is under way."""

    @property
    @abstractmethod
    def latest(self) -> TrainingSnapshot:
        """The latest snapshot of the session's training."""

    @abstractmethod
    def update(self) -> None:
        """Take in what the trainer has published."""

    @abstractmethod
    def start(self) -> bool:
        """Train until paused or the budget is reached; False when the budget is used up
        (or training cannot run: `error` says why)."""

    @abstractmethod
    def pause(self, wait: bool = True, timeout: float = ...) -> bool:
        """Stop training, mid-episode included; with `wait`, return once the session holds
        every episode trained (False on a timeout). A UI passes `wait=False`."""

    @abstractmethod
    def run_one_episode(self) -> bool:
        """Play one training episode (ignored while running or busy); False, as `start`."""

    @abstractmethod
    def run_one_step(self) -> bool:
        """Take one training step, explained in `last_event.last_update`, after those asked
        for before it (ignored while running or in an episode); False, as `start`."""

    @abstractmethod
    def set_hyperparameters(self, hp: Any) -> None:
        """New hyperparameters, taking effect at once (ValueError, changing nothing, if bad)."""

    @abstractmethod
    def wait_idle(self, timeout: float = ...) -> bool:
        """Wait until training holds nothing (nothing running, nothing asked for)."""

    @abstractmethod
    def close(self, wait: bool = True) -> None:
        """Stop training for good (with `wait`, return once it has ended)."""

    @abstractmethod
    def _speed_changed(self) -> None: ...

    @property
    def speed(self) -> Speed:
        return SPEEDS[self.speed_index]

    @property
    def last_scene(self) -> dict[str, Any] | None:
        """The board after the last animated step of the session's agent."""
        self.update()
        agent, scene, _ = self._shown
        return scene if agent is self.session.agent else None

    @property
    def last_event(self) -> StepEvent | None:
        """The last animated step of the session's agent."""
        self.update()
        agent, _, event = self._shown
        return event if agent is self.session.agent else None

    def set_speed(self, index: int) -> Speed:
        self.speed_index = max(0, min(len(SPEEDS) - 1, index))
        self._speed_changed()
        return self.speed

    def faster(self) -> Speed:
        return self.set_speed(self.speed_index + 1)

    def slower(self) -> Speed:
        return self.set_speed(self.speed_index - 1)
