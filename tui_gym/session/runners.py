"""`make_runner`: a runner of the kind asked for, behind the one `Runner` base."""

from __future__ import annotations

from typing import TYPE_CHECKING

from tui_gym.session.speeds import DEFAULT_SPEED, Runner

if TYPE_CHECKING:
    from tui_gym.session.session import Session

__all__ = ["RUNNERS", "make_runner"]

RUNNERS = ("thread", "process")


def make_runner(session: Session, kind: str = "thread", speed: int = DEFAULT_SPEED) -> Runner:
    """A runner of the given kind: "thread" (this process) or "process" (a child process)."""
    if kind == "thread":
        from tui_gym.session.runner import TrainingRunner

        return TrainingRunner(session, speed)
    if kind == "process":
        from tui_gym.session.process_runner import ProcessRunner

        return ProcessRunner(session, speed)
    raise ValueError(f"runner must be one of {', '.join(RUNNERS)}, got {kind!r}")
