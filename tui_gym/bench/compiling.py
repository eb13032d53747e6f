"""Compiling the learners: once with an empty cache (every algorithm made ready for every
game at once, as the engine's warm-up does, worker processes one per core), then loaded
from the disk cache in a fresh process."""

from __future__ import annotations

import json
import sys
import tempfile
import time
from dataclasses import dataclass

from tui_gym.bench.figures import child_json

TIMEOUT_S = 900.0


@dataclass(frozen=True)
class CompileResult:
    """Seconds: every learner compiled from nothing, Numba's import, the warm load."""

    cold_s: float
    import_s: float
    warm_s: float


def _child(kind: str) -> dict[str, float]:
    """The child's seconds: cold, every learner made ready on every game; warm, Numba's
    import and every learner loaded from the cache."""
    from tui_gym.algorithms import ALGORITHMS
    from tui_gym.core.engine import jit, loop

    began = time.perf_counter()
    if kind == "cold":
        from tui_gym.games import GAMES
        from tui_gym.session.session import Session

        sessions = [Session(game.name, algorithm=cls.name, seed=0)
                    for game in GAMES for cls in ALGORITHMS]
        agents = [session.trainer.agent for session in sessions]
        loop.warm([(x.name, x.arrays(), x.compiled_params()) for x in agents])
        for session in sessions:
            session.trainer.run(episodes=1)
            session.trainer.step()
            session.env.close()
        return {"seconds": time.perf_counter() - began}
    jit.start()
    imported = time.perf_counter()
    for cls in ALGORITHMS:
        learner = cls(4, n_states=4)
        loop.compile_learner(learner.arrays(), learner.compiled_params())
    return {"import": imported - began, "seconds": time.perf_counter() - imported}


def measure() -> CompileResult:
    """The cold compile and the warm load (see the module docstring)."""
    with tempfile.TemporaryDirectory(prefix="tui-gym-numba-") as folder:
        cold, warm = (child_json("tui_gym.bench.compiling", kind, what="compiling",
                                 timeout=TIMEOUT_S, env={"NUMBA_CACHE_DIR": folder})
                      for kind in ("cold", "warm"))
    return CompileResult(cold["seconds"], warm["import"], warm["seconds"])


if __name__ == "__main__":
    print(json.dumps(_child(sys.argv[1])))
