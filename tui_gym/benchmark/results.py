"""What a benchmark finds: `run_benchmark` plays one player through it, `BenchmarkResult`
holds the figures with 95% intervals (as rows or JSON), `record` keeps them in the run
history, and `leaderboard` lists a game's recorded runs, best first."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager, ExitStack
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.benchmark.referee import Fouls, Referee
from tui_gym.core.experiments import (
    Estimate,
    Figure,
    RunHistory,
    RunKind,
    RunRecorder,
    RunSpec,
    RunStatus,
    RunSummary,
    WrapperSetting,
    mean_with_ci,
    resolve_db_path,
)
from tui_gym.session.arena import EpisodeScore

if TYPE_CHECKING:
    from tui_gym.benchmark.players import Player


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
        ret, regret, times = self.mean_return, self.mean_regret, self.decision_ms()
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
        regret, times, fouls = self.mean_regret, self.decision_ms(), self.fouls
        settings = ", ".join(f"{k}={v}" for k, v in self.params.items()) or "defaults"
        if self.wrappers:
            settings += "; " + " ".join(self.wrappers)
        rows = [
            ("player", self.player),
            ("game", f"{self.game} ({settings})"),
            ("episodes", f"{self.episodes:,} (seeds {self.seed}–{self.seed + self.episodes - 1})"),
            ("mean return", _with_ci(self.mean_return)),
            ("exact regret per episode",
             _with_ci(regret, signed=False) if regret is not None
             else f"unavailable: {self.regret_note}"),
            ("agreement with the optimum",
             "–" if self.agreement is None
             else f"{self.agreed:,}/{self.decisions:,} decisions ({self.agreement:.1%})"),
            ("invalid actions", f"{fouls.invalid_actions:,}"),
            ("time-outs", f"{fouls.timeouts:,} (limit {self.decision_timeout:g} s a decision)"),
        ]
        rows += [(label, f"{count:,}{unit}") for label, count, unit in (
            ("played for a gone player", fouls.defaulted, " moves"),
            ("bad requests", fouls.bad_requests, ""), ("hints refused", fouls.hints_refused, ""),
        ) if count]
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


def run_benchmark(
    game: str, player: Player, *, episodes: int, seed: int, params: Mapping[str, Any] | None = None,
    wrappers: Sequence[str] = (), decision_timeout: float = 5.0, allow_hints: bool = False,
    recorder: Callable[[Any], AbstractContextManager[Any]] | None = None,
) -> BenchmarkResult:
    """Play `episodes` episodes of `game` (episode i on seed `seed + i`) with `player`;
    `recorder`, given the game's session, opens a recorder that writes every episode."""
    referee = Referee(game, episodes, seed, dict(params or {}), tuple(wrappers), allow_hints)
    played: list[EpisodeScore] = []
    referee.seat.score.history = played
    started = time.perf_counter()
    try:
        with ExitStack() as stack:
            if recorder is not None:
                handler = referee.seat.handler
                handler.game.recorder = stack.enter_context(recorder(handler.session))
            outcome = player.play(referee, decision_timeout)
    finally:
        referee.close()
    seconds = time.perf_counter() - started
    score = referee.seat.score
    regrets = [e.exact_regret for e in played]
    exact = all(r is not None for r in regrets)
    note = ""
    if not exact:
        why = "; ".join(sorted(score.notes)) or "the game gives no exact action values"
        counted = [text for count, text in (
            (score.unscored, f"{score.unscored:,} of {score.decisions:,} decisions"),
            (score.unjudged, f"{score.unjudged:,} moves not judged")) if count]
        note = f"{why} ({'; '.join(counted)})"
    return BenchmarkResult(
        game=referee.entry.name, env_id=referee.entry.env_id, params=referee.params,
        wrappers=referee.wrappers, player=player.label, episodes=len(played), seed=seed,
        decision_timeout=decision_timeout, allow_hints=allow_hints,
        returns=np.array([e.episode_return for e in played], dtype=np.float64),
        regrets=np.array(regrets, dtype=np.float64) if exact else None, regret_note=note,
        decisions=score.decisions, agreed=score.agreed, fouls=referee.fouls,
        decision_times=np.array(outcome.decision_times, dtype=np.float64), status=outcome.status,
        stderr_tail=outcome.stderr_tail, seconds=seconds,
    )


def record(result: BenchmarkResult, db: str | None = None) -> int:
    """Write `result` into the run history (`--db`, else the default); its run id."""
    from tui_gym.core.wrappers import parse_wrapper_spec

    wrappers = [WrapperSetting(c.name, c.values())
                for c in map(parse_wrapper_spec, result.wrappers)]
    spec = RunSpec(RunKind.BENCHMARK, result.game, result.player, result.params, wrappers, {
        "episodes": result.episodes, "first_seed": result.seed,
        "decision_timeout": result.decision_timeout, "allow_hints": result.allow_hints,
    }, seeds=(result.seed,))
    fouls, regret, times = result.fouls, result.mean_regret, result.decision_ms()
    figures = [
        Figure("episodes", result.episodes), result.mean_return.figure("mean_return"),
        Figure("decisions", result.decisions), Figure("invalid_actions", fouls.invalid_actions),
        Figure("timeouts", fouls.timeouts), Figure("defaulted", fouls.defaulted),
        *([] if regret is None else [regret.figure("regret_per_episode")]),
        *([] if result.agreement is None else [Figure("agreement", result.agreement)]),
        *([] if times is None else [Figure("decision_ms_median", times[0], "ms")]),
    ]
    with RunHistory(resolve_db_path(db)) as history:
        recorder = RunRecorder(history, spec)
        recorder.extend("return", result.returns)
        if result.regrets is not None:
            recorder.extend("regret", result.regrets)
        recorder.add_figures(*figures)
        recorder.finish(RunStatus.FINISHED)
        return recorder.run_id


def _key(run: RunSummary) -> tuple[bool, float, float]:
    regret = run.figure("regret_per_episode")
    ret = run.figure("mean_return")
    mean_return = ret.value if ret is not None and math.isfinite(ret.value) else -math.inf
    if regret is not None and math.isfinite(regret.value):
        return (False, regret.value, -mean_return)
    return (True, -mean_return, 0.0)


def leaderboard(game: str, db: str | None = None) -> tuple[str, list[RunSummary]]:
    """The run history's path, and `game`'s finished benchmark runs, best first."""
    path = resolve_db_path(db)
    if not path.exists() or path.stat().st_size == 0:
        return str(path), []
    with RunHistory(path) as history:
        runs = history.list_runs(game=game, kind=RunKind.BENCHMARK)
    return str(path), sorted((r for r in runs if r.status is RunStatus.FINISHED), key=_key)
