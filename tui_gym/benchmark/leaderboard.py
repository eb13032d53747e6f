"""Benchmark results in the run history, and the leaderboard: a game's runs, best first."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from tui_gym.benchmark.results import BenchmarkResult
from tui_gym.core.experiments import (
    Figure,
    RunHistory,
    RunKind,
    RunRecorder,
    RunSpec,
    RunStatus,
    RunSummary,
    WrapperSetting,
    resolve_db_path,
)


def record(result: BenchmarkResult, db: str | None = None) -> int:
    """Write `result` into the run history (`--db`, else the default); its run id."""
    from tui_gym.core.wrappers import parse_wrapper_spec

    wrappers = []
    for text in result.wrappers:
        choice = parse_wrapper_spec(text)
        wrappers.append(WrapperSetting(choice.name, choice.values()))
    spec = RunSpec(
        kind=RunKind.BENCHMARK,
        game=result.game,
        algorithm=result.player,
        game_params=result.params,
        wrappers=wrappers,
        hyperparameters={
            "episodes": result.episodes, "first_seed": result.seed,
            "decision_timeout": result.decision_timeout, "allow_hints": result.allow_hints,
        },
        seeds=(result.seed,),
    )
    ret = result.mean_return
    figures = [
        Figure("episodes", result.episodes), ret.figure("mean_return"),
        Figure("decisions", result.decisions),
        Figure("invalid_actions", result.fouls.invalid_actions),
        Figure("timeouts", result.fouls.timeouts), Figure("defaulted", result.fouls.defaulted),
    ]
    regret = result.mean_regret
    if regret is not None:
        figures.append(regret.figure("regret_per_episode"))
    if result.agreement is not None:
        figures.append(Figure("agreement", result.agreement))
    times = result.decision_ms()
    if times is not None:
        figures.append(Figure("decision_ms_median", times[0], "ms"))
    with RunHistory(resolve_db_path(db)) as history:
        recorder = RunRecorder(history, spec)
        recorder.extend("return", result.returns)
        if result.regrets is not None:
            recorder.extend("regret", result.regrets)
        recorder.add_figures(*figures)
        recorder.finish(RunStatus.FINISHED)
        return recorder.run_id


@dataclass(frozen=True)
class Standing:
    """One run on the leaderboard."""

    rank: int
    run: RunSummary

    def value(self, name: str) -> Figure | None:
        return self.run.figure(name)

    def to_json(self) -> dict[str, Any]:
        return {"rank": self.rank, **self.run.to_json()}


def _key(run: RunSummary) -> tuple[bool, float, float]:
    regret = run.figure("regret_per_episode")
    ret = run.figure("mean_return")
    mean_return = ret.value if ret is not None and math.isfinite(ret.value) else -math.inf
    if regret is not None and math.isfinite(regret.value):
        return (False, regret.value, -mean_return)
    return (True, -mean_return, 0.0)


def leaderboard(game: str, db: str | None = None) -> tuple[str, list[Standing]]:
    """The run history's path, and `game`'s finished benchmark runs, best first."""
    path = resolve_db_path(db)
    if not path.exists() or path.stat().st_size == 0:
        return str(path), []
    with RunHistory(path) as history:
        runs = history.list_runs(game=game, kind=RunKind.BENCHMARK)
    runs = [r for r in runs if r.status is RunStatus.FINISHED]
    runs.sort(key=_key)
    return str(path), [Standing(i + 1, run) for i, run in enumerate(runs)]
