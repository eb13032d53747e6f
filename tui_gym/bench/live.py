"""Live training: what the real app does to training speed, its refresh rate and key latency."""

from __future__ import annotations

import asyncio
import contextlib
import gc
import random
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from tui_gym.algorithms import QLearning
from tui_gym.bench.figures import median, percentile
from tui_gym.session.session import Session

RUNNERS = ("thread", "process")
DEFAULT_RUNNER = "process"  # what `tui-gym` (run_app) opens the app with
LIVE_BUDGET = 1_000_000_000  # episodes: never reached, so training stays at max speed
WARMUP_SECONDS = 0.5  # after the first snapshot of the run
SIZE = (120, 40)
WAIT_TIMEOUT = 20.0  # seconds; only reached when something is broken
PAUSE_RANGE = (0.15, 0.4)  # seconds before each key press: a person's pace, not a key storm


@dataclass(frozen=True)
class KeySample:
    """One key press: what it was and where its time went (milliseconds)."""

    key: str
    total_ms: float
    queue_ms: float
    action_ms: float
    frame_ms: float


@dataclass(frozen=True)
class LiveRepeat:
    """One headless + live + key-latency repeat for one runner."""

    headless_eps: float
    live_eps: float
    refresh_hz: float
    frames_hz: float
    engine: str
    keys: tuple[KeySample, ...]

    @property
    def ratio(self) -> float:
        return self.live_eps / self.headless_eps if self.headless_eps else float("nan")


@dataclass(frozen=True)
class LiveResult:
    """One runner's figures: medians over repeats; latency percentiles over all presses."""

    runner: str
    repeats: tuple[LiveRepeat, ...]
    seconds: float  # the measuring window
    errors: tuple[str, ...] = field(default=())

    def _median(self, name: str) -> float:
        return median([getattr(r, name) for r in self.repeats])

    live_ratio = property(lambda self: self._median("ratio"))
    headless_eps = property(lambda self: self._median("headless_eps"))
    live_eps = property(lambda self: self._median("live_eps"))
    refresh_hz = property(lambda self: self._median("refresh_hz"))

    def key_latency_ms(self, q: float) -> float:
        return percentile([k.total_ms for r in self.repeats for k in r.keys], q)

    @property
    def presses(self) -> int:
        return sum(len(r.keys) for r in self.repeats)


def headless_rate(seconds: float, seed: int = 0) -> float:
    """Episodes per second of the default engine ("auto") trained headless in this process."""
    session = Session(hp=QLearning.hyperparameters(episodes=LIVE_BUDGET), seed=seed)
    trainer = session.trainer
    trainer.run(seconds=0.2)
    start = time.perf_counter()
    done = trainer.run(seconds=seconds)
    elapsed = time.perf_counter() - start
    session.env.close()
    return done / elapsed


# --- instrumenting the app ------------------------------------------------------
class _Instruments:
    """Counters and clocks hooked onto one app instance (never onto its class)."""

    def __init__(self, app: Any) -> None:
        self.frames: list[tuple[float, str | None, str | None]] = []  # (time, view, focus's view)
        self.snapshots: list[float] = []  # when each snapshot was drawn
        self.action_marks: list[tuple[float, float]] = []  # (start, end) of show_view
        on_frames(app, lambda: self.frames.append(
            (time.perf_counter(), _current_view(app), _focus_view(app))))
        after_each(app, "action_show_view",
                   lambda began, *_: self.action_marks.append((began, time.perf_counter())))


def after_each(target: Any, name: str, then: Callable[..., None]) -> None:
    """Have `target.name(*args)` (on this instance only) call `then(started, *args)` after."""
    call = getattr(target, name)

    def hooked(*args: Any, **kwargs: Any) -> Any:
        started = time.perf_counter()
        result = call(*args, **kwargs)
        then(started, *args)
        return result

    setattr(target, name, hooked)


def on_frames(app: Any, frame: Callable[[], None]) -> None:
    """Call `frame()` as each frame of `app` has been written out (rendered as a real
    terminal's write would render it)."""
    from tui_gym.ui.textual_internals import watch_frames

    def on_frame(renderable: Any) -> None:
        render = getattr(renderable, "render_segments", None)
        if render is not None:
            render(app.console)  # what a real terminal's write costs
        frame()

    if not watch_frames(app, on_frame):
        raise RuntimeError("this Textual has no frame step to time keys by")


def _current_view(app: Any) -> str | None:
    try:
        return app.current_view
    except Exception:  # while the app is being taken apart
        return None


def _focus_view(app: Any) -> str | None:
    """"play" or "train": the view that holds the focused widget (None: neither)."""
    with contextlib.suppress(Exception):  # while the app is being taken apart
        focused = app.focused
        for view in ("play", "train"):
            if focused is not None and app.query_one(f"#{view}") in focused.ancestors_with_self:
                return view
    return None


def _send_key(app: Any, key: str) -> None:
    """Deliver a key the way `Pilot.press` does (and a terminal's input thread)."""
    from textual import events

    from tui_gym.ui.textual_internals import deliver_key

    char = " " if key == "space" else key if len(key) == 1 else None
    event = events.Key(key, char)
    event.set_sender(app)
    deliver_key(app, event)


async def _until(predicate: Callable[[], bool], what: str, timeout: float = WAIT_TIMEOUT) -> None:
    deadline = time.perf_counter() + timeout
    while not predicate():
        if time.perf_counter() > deadline:
            raise TimeoutError(f"timed out waiting for {what}")
        await asyncio.sleep(0.002)


async def press(app: Any, key: str, rng: random.Random, answered: Callable[[], float | None],
                what: str) -> tuple[float, float]:
    """After a person's pause, press `key`; when it was sent, and the time `answered()`
    gives once the answer is on screen."""
    await asyncio.sleep(rng.uniform(*PAUSE_RANGE))
    sent = time.perf_counter()
    _send_key(app, key)
    await _until(lambda: answered() is not None, what)
    return sent, answered()  # type: ignore[return-value]


async def _fresh_snapshot(runner: Any) -> tuple[int, float]:
    """Wait for the next snapshot; its episode count and when it showed up."""
    version = runner.latest.version
    await _until(lambda: runner.latest.version != version, "a new snapshot")
    return runner.latest.episodes, time.perf_counter()


async def _key_latencies(
    app: Any, tools: _Instruments, presses: int, rng: random.Random
) -> list[KeySample]:
    samples = []
    for _ in range(presses):
        key, target = ("p", "play") if _current_view(app) == "train" else ("t", "train")
        frames_before, actions_before = len(tools.frames), len(tools.action_marks)

        def shown(frames_before: int = frames_before, target: str = target) -> float | None:
            return next((t for t, view, focus in tools.frames[frames_before:]
                         if view == focus == target), None)

        sent, frame_at = await press(app, key, rng, shown, f"the {target} view, with the focus")
        marks = tools.action_marks[actions_before:]
        began, ended = marks[0] if marks else (sent, sent)
        samples.append(KeySample(
            key=key, total_ms=(frame_at - sent) * 1000, queue_ms=(began - sent) * 1000,
            action_ms=(ended - began) * 1000, frame_ms=(frame_at - ended) * 1000,
        ))
    return samples


async def _live_once(runner_kind: str, seconds: float, presses: int, seed: int,
                     headless: float) -> LiveRepeat:
    from tui_gym.ui.app import TuiGymApp

    session = Session(hp=QLearning.hyperparameters(episodes=LIVE_BUDGET), seed=seed)
    app = TuiGymApp(session, runner=runner_kind, tune_gc=True)  # as `tui-gym` runs it
    tools = _Instruments(app)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("t")  # idle still, so the pilot's own waits are short
        await _until(lambda: _current_view(app) == "train", "the Train view")
        after_each(app.train_view, "show_snapshot", lambda *_: tools.snapshots.append(0.0))
        runner = app.runner
        _send_key(app, "space")
        await _until(lambda: runner.running and runner.latest.episodes > 0, "training to start")
        await asyncio.sleep(WARMUP_SECONDS)
        episodes0, t0 = await _fresh_snapshot(runner)
        calls0, frames0 = len(tools.snapshots), len(tools.frames)
        await asyncio.sleep(seconds)
        episodes1, t1 = await _fresh_snapshot(runner)
        elapsed = t1 - t0
        done = LiveRepeat(headless, (episodes1 - episodes0) / elapsed,
                          (len(tools.snapshots) - calls0) / elapsed,
                          (len(tools.frames) - frames0) / elapsed, runner.latest.engine,
                          tuple(await _key_latencies(app, tools, presses, random.Random(seed))))
        if not runner.running:
            raise RuntimeError(f"training stopped during the measurement: {runner.error}")
        runner.pause()
    return done


def _repeat(runner_kind: str, seconds: float, presses: int, seed: int) -> LiveRepeat:
    """One headless + live pair for one runner."""
    gc.collect()
    headless = headless_rate(seconds, seed)
    gc.collect()
    return asyncio.run(_live_once(runner_kind, seconds, presses, seed, headless))


def measure(
    seconds: float, presses: int, repeats: int, runners: Sequence[str] = RUNNERS,
    progress: Callable[[str], None] | None = None,
) -> dict[str, LiveResult]:
    """`repeats` headless + live pairs for every runner in turn; a runner that fails is
    reported with its error, not raised."""
    results = {}
    for kind in runners:
        if progress is not None:
            progress(f"live training, {kind} runner")
        try:
            done = tuple(_repeat(kind, seconds, presses, seed) for seed in range(repeats))
            results[kind] = LiveResult(kind, done, seconds)
        except Exception as exc:  # one broken runner must not hide the other's figures
            results[kind] = LiveResult(kind, (), seconds, (f"{type(exc).__name__}: {exc}",))
    return results
