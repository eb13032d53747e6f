"""Training speeds and the `Runner` protocol every runner (thread, child process) follows.

Speeds run from *animated* (one agent step at a time, slow enough to follow,
with the last move kept for a board to draw) to *max* (whole chunks of
episodes, no pauses). A front end drives any runner through `Runner`; which
one it gets is `tui_gym.session.runners.make_runner`'s business.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

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


class Runner(Protocol):
    """What a front end asks of a runner: controls, the latest snapshot, the last move."""

    session: Session
    error: BaseException | None
    finished: bool

    @property
    def speed(self) -> Speed: ...

    @property
    def running(self) -> bool: ...

    @property
    def busy(self) -> bool: ...

    @property
    def latest(self) -> TrainingSnapshot: ...

    @property
    def last_scene(self) -> dict[str, Any] | None: ...

    @property
    def last_event(self) -> StepEvent | None: ...

    def update(self) -> None: ...

    def start(self) -> bool: ...

    def pause(self, wait: bool = True, timeout: float = ...) -> Any: ...

    def toggle(self) -> bool: ...

    def run_one_episode(self) -> bool: ...

    def run_one_step(self) -> bool: ...

    def set_hyperparameters(self, hp: Any) -> None: ...

    def set_speed(self, index: int) -> Speed: ...

    def faster(self) -> Speed: ...

    def slower(self) -> Speed: ...

    def wait_idle(self, timeout: float = ...) -> bool: ...

    def close(self, wait: bool = True) -> None: ...
