"""Defaults that reach their bound: the share of seeds, per game and algorithm."""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

from tui_gym.core.engine import processes
from tui_gym.core.mdp import NotAvailable

SEEDS = 40


@dataclass(frozen=True)
class DefaultsResult:
    """How many of `seeds` runs met the bound, and the worst figure among them."""

    game: str
    algorithm: str
    bound: str
    met: int
    seeds: int
    worst: float
    lesson: str = ""  # why the defaults end short by the learner's nature, if they do

    @property
    def share(self) -> float:
        return self.met / self.seeds if self.seeds else math.nan


def one_run(game: str, algorithm: str, seed: int) -> tuple[bool, float, str, bool, str]:
    """Whether a default run meets the game's bound, its figure, the bound in words,
    whether it is a least value (else a most) and the game's lesson for the algorithm."""
    from tui_gym.session.session import Session

    session = Session(game, algorithm=algorithm, seed=seed)
    bound = session.game.oracle.bound(session.env_kwargs, session.changes)
    assert not isinstance(bound, NotAvailable), bound
    session.train()
    reference = session.reference()
    assert reference is not None
    value = float(reference.figures[bound.figure])
    session.env.close()
    lesson = session.game.lessons.get(session.algorithm, "")
    return bound.met(reference.figures), value, bound.text, bound.at_least, lesson


def measure(games: Sequence[str], algorithms: Sequence[str], seeds: int = SEEDS,
            workers: int | None = None) -> tuple[DefaultsResult, ...]:
    """`one_run` for every game, algorithm and seed, spread over child processes."""
    pairs = [(game, algorithm) for game in games for algorithm in algorithms]
    with ProcessPoolExecutor(max_workers=workers, mp_context=processes.context()) as pool:
        futures = {pair: [pool.submit(one_run, *pair, seed) for seed in range(seeds)]
                   for pair in pairs}
        out = []
        for (game, algorithm), runs in futures.items():
            found = [run.result() for run in runs]
            values = [f[1] for f in found]
            _, _, text, at_least, lesson = found[0]
            out.append(DefaultsResult(game, algorithm, text, sum(f[0] for f in found), seeds,
                                      min(values) if at_least else max(values), lesson))
    return tuple(out)
