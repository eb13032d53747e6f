"""How the app paces its work: frames drawn soon after a change, garbage
collected between frames rather than in the middle of one."""

from __future__ import annotations

import os
import subprocess
import sys


def test_the_app_collects_garbage_on_its_own_timers() -> None:
    import gc

    from tui_gym.ui import app as app_module

    class Timers:
        def __init__(self) -> None:
            self.made: list[tuple[float, object]] = []

        def set_interval(self, seconds: float, callback: object, name: str = "") -> None:
            self.made.append((seconds, callback))

    timers = Timers()
    try:
        app_module.tune_gc_for_ui(timers)  # type: ignore[arg-type]
        assert not gc.isenabled(), "collections would still land in the middle of frames"
        periods = sorted(seconds for seconds, _ in timers.made)
        assert periods == [app_module.YOUNG_GC_SECONDS, app_module.FULL_GC_SECONDS]

        collected: list[int] = []

        def heard(phase: str, info: dict) -> None:
            if phase == "stop":
                collected.append(info["generation"])

        gc.callbacks.append(heard)
        try:
            for _seconds, callback in sorted(timers.made, key=lambda made: made[0]):
                callback()  # type: ignore[operator]
        finally:
            gc.callbacks.remove(heard)
        assert collected == [1, 2], "young generations first, then everything"
    finally:
        gc.enable()
        gc.unfreeze()


def _update_period(env: dict[str, str]) -> float:
    code = "import tui_gym.ui.app, textual.screen as s; print(s.UPDATE_PERIOD)"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, timeout=60)
    return float(out.stdout)


def test_the_app_draws_a_change_within_a_few_milliseconds() -> None:
    from tui_gym.ui import MAX_FPS

    env = {k: v for k, v in os.environ.items() if k != "TEXTUAL_FPS"}
    assert _update_period(env) == 1 / MAX_FPS
    assert 1 / MAX_FPS <= 0.005  # a skipped tick then costs at most 10 ms


def test_a_frame_rate_set_by_the_user_is_kept() -> None:
    env = {**os.environ, "TEXTUAL_FPS": "30"}
    assert _update_period(env) == 1 / 30


def test_a_young_collection_due_just_after_a_key_waits_one_turn() -> None:
    import gc
    import time

    from tui_gym.ui.app import GcPacer

    collected: list[int] = []

    def heard(phase: str, info: dict) -> None:
        if phase == "stop":
            collected.append(info["generation"])

    gc.disable()  # only the pacer's collections are heard
    gc.callbacks.append(heard)
    try:
        answering = GcPacer(key_since=time.monotonic)  # a key handed on just now
        answering.collect_young()
        assert collected == [] and answering.young_postponed == 1
        answering.collect_young()  # the next turn collects, key or not
        assert collected == [1] and answering.young_collections == 1
        idle = GcPacer()  # no key
        idle.collect_young()
        assert collected == [1, 1] and idle.young_postponed == 0
    finally:
        gc.callbacks.remove(heard)
        gc.enable()
