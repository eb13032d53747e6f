"""Memory: how much the resident set grows over a long training run."""

from __future__ import annotations

import gc
import json
import os
import sys
from dataclasses import dataclass

from tui_gym.bench.figures import child_json

MB = 1024 * 1024
CHUNK_SECONDS = 0.05  # as the app's runner (`core.runner.CHUNK_SECONDS`)


@dataclass(frozen=True)
class MemoryResult:
    """RSS growth over `episodes` training episodes after `warmup` episodes."""

    episodes: int
    warmup: int
    engine: str
    rss_start_mb: float
    rss_end_mb: float
    rss_peak_mb: float
    seconds: float


def rss_bytes() -> int:
    """This process's resident set size now (its peak where /proc is missing)."""
    try:
        with open("/proc/self/statm") as f:
            resident_pages = int(f.read().split()[1])
        return resident_pages * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        import resource

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak if sys.platform == "darwin" else peak * 1024


def train_and_watch(episodes: int, warmup: int, engine: str = "auto") -> dict[str, float | str]:
    """The measurement itself (run in the child process); figures as a dict."""
    import time

    from tui_gym.algorithms import QLearning
    from tui_gym.session.session import Session

    hp = QLearning.hyperparameters(episodes=warmup + episodes)
    session = Session(hp=hp, seed=0, engine=engine)
    trainer = session.trainer
    trainer.run(episodes=warmup)
    gc.collect()
    start = rss_bytes()
    peak = start
    began = time.perf_counter()
    while trainer.remaining > 0:
        trainer.run(episodes=trainer.remaining, seconds=CHUNK_SECONDS)
        peak = max(peak, rss_bytes())
    seconds = time.perf_counter() - began
    gc.collect()
    end = rss_bytes()
    return {
        "episodes": trainer.episodes - warmup, "warmup": warmup, "engine": trainer.engine,
        "rss_start_mb": start / MB, "rss_end_mb": end / MB, "rss_peak_mb": max(peak, end) / MB,
        "seconds": seconds,
    }


def measure(episodes: int, warmup: int, engine: str = "auto") -> MemoryResult:
    """Run `train_and_watch` in a fresh interpreter and read its figures."""
    return MemoryResult(**child_json("tui_gym.bench.memory", str(episodes), str(warmup), engine,
                                     what="the memory run", timeout=600))


if __name__ == "__main__":
    print(json.dumps(train_and_watch(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])))
