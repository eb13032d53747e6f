"""`run_benchmark`: one player through every episode of a referee's benchmark."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from contextlib import AbstractContextManager, ExitStack
from typing import Any

import numpy as np

from tui_gym.benchmark.players import Player
from tui_gym.benchmark.referee import Referee
from tui_gym.benchmark.results import BenchmarkResult
from tui_gym.session.arena import EpisodeScore
from tui_gym.session.arena.games import attach_recorder


def run_benchmark(
    game: str, player: Player, *, episodes: int, seed: int, params: Mapping[str, Any] | None = None,
    wrappers: Sequence[str] = (), decision_timeout: float = 5.0, allow_hints: bool = False,
    recorder: Callable[[Any], AbstractContextManager[Any]] | None = None,
) -> BenchmarkResult:
    """Play `episodes` episodes of `game` (episode i on seed `seed + i`) with `player`;
    `recorder`, given the game's session, opens a recorder that writes every episode."""
    if not decision_timeout > 0:
        raise ValueError(f"the decision time limit must be positive, got {decision_timeout}")
    referee = Referee(game, episodes, seed, dict(params or {}), tuple(wrappers), allow_hints)
    played: list[EpisodeScore] = []
    referee.seat.score.history = played
    started = time.perf_counter()
    try:
        with ExitStack() as stack:
            if recorder is not None:
                handler = referee.seat.handler
                attach_recorder(handler, stack.enter_context(recorder(handler.session)))
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
        counted = [f"{score.unscored:,} of {score.decisions:,} decisions"] if score.unscored \
            else []
        if score.unjudged:
            counted.append(f"{score.unjudged:,} moves not judged")
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
