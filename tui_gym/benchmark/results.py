"""`BenchmarkResult`: what a benchmark measured, with 95% intervals, as rows or JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tui_gym.benchmark.referee import Fouls
from tui_gym.core.experiments import Estimate, mean_with_ci


@dataclass(frozen=True)
class BenchmarkResult:
    """One player's benchmark on one game."""

    game: str  # the game's short name
    env_id: str
    params: dict[str, Any]
    wrappers: tuple[str, ...]
    player: str
    episodes: int
    seed: int
    decision_timeout: float
    allow_hints: bool
    returns: np.ndarray  # one per episode
    regrets: np.ndarray | None  # exact regret per episode, None when unavailable
    regret_note: str
    decisions: int
    agreed: int
    fouls: Fouls
    decision_times: np.ndarray  # seconds, one per decision the player made
    status: str  # how the player ended, in words
    stderr_tail: str = ""
    seconds: float = 0.0
    run_id: int | None = field(default=None, compare=False)

    @property
    def mean_return(self) -> Estimate:
        return mean_with_ci(self.returns)

    @property
    def mean_regret(self) -> Estimate | None:
        return None if self.regrets is None else mean_with_ci(self.regrets)

    @property
    def agreement(self) -> float | None:
        return self.agreed / self.decisions if self.decisions else None

    def decision_ms(self) -> tuple[float, float] | None:
        """Median and 95th percentile of the time per decision, in ms."""
        if not len(self.decision_times):
            return None
        p50, p95 = np.percentile(self.decision_times, [50, 95])
        return float(p50) * 1e3, float(p95) * 1e3

    def to_json(self) -> dict[str, Any]:
        ret = self.mean_return
        regret = self.mean_regret
        times = self.decision_ms()
        return {
            "game": self.game, "env_id": self.env_id, "params": self.params,
            "wrappers": list(self.wrappers), "player": self.player, "episodes": self.episodes,
            "seeds": [self.seed, self.seed + self.episodes - 1],
            "decision_timeout": self.decision_timeout, "allow_hints": self.allow_hints,
            "mean_return": ret.mean, "return_ci95": ret.ci95,
            "mean_regret": None if regret is None else regret.mean,
            "regret_ci95": None if regret is None else regret.ci95, "regret_note": self.regret_note,
            "decisions": self.decisions, "agreement": self.agreement, **self.fouls.to_json(),
            "decision_ms_median": None if times is None else times[0],
            "decision_ms_p95": None if times is None else times[1], "player_status": self.status,
            "player_stderr": self.stderr_tail, "seconds": self.seconds, "run_id": self.run_id,
        }

    def rows(self) -> list[tuple[str, str]]:
        """The result as (label, value) rows for people."""
        ret = self.mean_return
        regret = self.mean_regret
        times = self.decision_ms()
        fouls = self.fouls
        settings = ", ".join(f"{k}={v}" for k, v in self.params.items()) or "defaults"
        if self.wrappers:
            settings += "; " + " ".join(self.wrappers)
        rows = [
            ("player", self.player),
            ("game", f"{self.game} ({settings})"),
            ("episodes", f"{self.episodes:,} (seeds {self.seed}–{self.seed + self.episodes - 1})"),
            ("mean return", _with_ci(ret)),
            ("exact regret per episode",
             _with_ci(regret, signed=False) if regret is not None
             else f"unavailable: {self.regret_note}"),
            ("agreement with the optimum",
             "–" if self.agreement is None
             else f"{self.agreed:,}/{self.decisions:,} decisions ({self.agreement:.1%})"),
            ("invalid actions", f"{fouls.invalid_actions:,}"),
            ("time-outs", f"{fouls.timeouts:,} (limit {self.decision_timeout:g} s a decision)"),
        ]
        if fouls.defaulted:
            rows.append(("played for a gone player", f"{fouls.defaulted:,} moves"))
        if fouls.bad_requests:
            rows.append(("bad requests", f"{fouls.bad_requests:,}"))
        if fouls.hints_refused:
            rows.append(("hints refused", f"{fouls.hints_refused:,}"))
        rows.append(("time per decision",
                     "–" if times is None else f"{times[0]:.3f} ms median, {times[1]:.3f} ms p95"))
        rows.append(("how the player ended", self.status))
        if self.stderr_tail:
            rows.append(("its stderr (last lines)", self.stderr_tail))
        return rows


def _with_ci(estimate: Estimate, signed: bool = True) -> str:
    mean = f"{estimate.mean:+.4f}" if signed else f"{estimate.mean:.4f}"
    if estimate.ci95 is None:
        return mean
    return f"{mean} ± {estimate.ci95:.4f} (95% CI)"
