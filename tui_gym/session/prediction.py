"""A prediction learner's figures in a session: its V against the exact V^π, state by state."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PredictionFigures"]


@dataclass(frozen=True)
class PredictionFigures:
    """The RMS error of V, and per reached model state its estimate and true value."""

    rms: float
    states: tuple[int, ...]
    estimate: tuple[float, ...]
    truth: tuple[float, ...]
