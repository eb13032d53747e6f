"""`LatestOnly`: the views' exact figures computed off the event loop, one at a time, never
while a key is answered, resting after each; the Play view's scoreboard computed so, and
the Train view's snapshots waiting while a key is answered."""

from __future__ import annotations

import threading
import time

import pytest
from textual import on
from textual.app import App, ComposeResult
from textual.widget import Widget

from tui_gym.algorithms import QLearning
from tui_gym.session.session import Session
from tui_gym.ui import exact_figures
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.exact_figures import TURNS, LatestOnly, key_wait_of

from .hosts import VIEW_SIZE, PlayHost, TrainHost
from .waiting import DEADLINE, open_train, wait_until


class Keys:
    """A key being answered (`wait` > 0) or not, as `LatestOnly.key_wait` reads it."""

    def __init__(self) -> None:
        self.wait = 0.0

    def __call__(self) -> float:
        return self.wait


class Box(Widget):
    """Asks for squares of numbers; keeps what comes back."""

    def __init__(self, keys: Keys, work=None) -> None:
        super().__init__()
        self.computed: list[int] = []  # what the work was asked, in order
        self.results: list[int | None] = []
        self.exact: LatestOnly[int, int] = LatestOnly(self, work or self.square, keys)

    def square(self, n: int) -> int:
        self.computed.append(n)
        return n * n

    @on(LatestOnly.Computed)
    def _computed(self, message: LatestOnly.Computed) -> None:
        message.stop()
        result = message.owner.done(message)
        if result is not None:
            self.results.append(result)


class BoxHost(App[None]):
    def __init__(self, *boxes: Box) -> None:
        super().__init__()
        self.boxes = boxes

    def compose(self) -> ComposeResult:
        yield from self.boxes


@pytest.fixture(autouse=True)
def no_rest(monkeypatch) -> None:
    monkeypatch.setattr(TURNS, "rest_until", 0.0)  # none left over from another test


async def test_a_key_being_answered_holds_the_computation_and_the_latest_wins() -> None:
    keys = Keys()
    box = Box(keys)
    async with BoxHost(box).run_test() as pilot:
        keys.wait = 1.0  # a key was just handed on
        box.exact.ask(2)
        await wait_until(pilot, lambda: box.exact.held, "the worker held")
        box.exact.ask(3)  # a newer snapshot replaces the one waiting
        assert box.computed == [] and not box.exact.idle
        keys.wait = 0.0  # the key's frame is drawn
        await wait_until(pilot, lambda: box.exact.idle, "the figures")
        assert box.computed == [3] and box.results == [9]


async def test_a_result_waits_while_a_key_is_answered() -> None:
    keys = Keys()

    def square_then_key(n: int) -> int:
        keys.wait = 1.0  # a key comes while it computes
        return n * n

    box = Box(keys, square_then_key)
    async with BoxHost(box).run_test() as pilot:
        box.exact.ask(4)
        await wait_until(pilot, lambda: box.exact.held, "the result held")
        assert box.results == []
        keys.wait = 0.0
        await wait_until(pilot, lambda: box.results, "the result")
        assert box.results == [16]


async def test_the_views_compute_one_at_a_time() -> None:
    release = threading.Event()
    keys = Keys()

    def slow(n: int) -> int:
        release.wait(DEADLINE)
        return -n

    first, second = Box(keys, slow), Box(keys)
    async with BoxHost(first, second).run_test() as pilot:
        first.exact.ask(1)
        await wait_until(pilot, lambda: TURNS.lock.locked(), "the first computing")
        second.exact.ask(5)
        for _ in range(5):  # the second's worker runs and waits on the first
            await pilot.pause(0.02)
        assert second.computed == []
        release.set()
        await wait_until(pilot, lambda: second.results, "the second's result")
        assert first.results == [-1] and second.results == [25]


async def test_the_next_computation_rests_as_long_as_the_last_took(monkeypatch) -> None:
    class Clock:
        """Time stands still until the test moves it; each computation takes 0.2 s of CPU."""

        now = 100.0
        cpu = 0.0

        def monotonic(self) -> float:
            return self.now

        def thread_time(self) -> float:
            self.cpu += 0.1  # read before and after: 0.2 s apart
            return self.cpu

        def sleep(self, seconds: float) -> None:
            time.sleep(0.001)

    clock = Clock()
    monkeypatch.setattr(exact_figures, "time", clock)
    box = Box(Keys())
    async with BoxHost(box).run_test() as pilot:
        box.exact.ask(2)
        await wait_until(pilot, lambda: box.results == [4], "the first result")
        assert TURNS.rest_until == pytest.approx(100.1)
        box.exact.ask(3)
        await wait_until(pilot, lambda: box.exact.held, "the next one resting")
        assert box.computed == [2]
        clock.now = 100.2
        await wait_until(pilot, lambda: box.results == [4, 9], "the next result")


def test_key_wait_reads_when_the_app_handed_a_key_on() -> None:
    class Keyed:
        _key_since = 0.0

    app = Keyed()
    assert key_wait_of(app) == 0.0  # no key yet
    app._key_since = time.monotonic()
    assert 0.0 < key_wait_of(app) <= exact_figures.KEY_QUIET_SECONDS
    app._key_since = time.monotonic() - exact_figures.KEY_QUIET_SECONDS
    assert key_wait_of(app) <= 0.0
    assert key_wait_of(object()) == 0.0  # an app that does not keep its keys in order


def test_key_wait_lasts_until_the_keys_frame_is_drawn(monkeypatch) -> None:
    class Keyed:
        _key_since = 0.0

    app = Keyed()
    drawn = [0.0]
    monkeypatch.setitem(exact_figures._DRAWN, app, drawn)
    # A key handed on past its quiet time, its frame not drawn yet: the figures wait.
    app._key_since = time.monotonic() - exact_figures.KEY_QUIET_SECONDS
    assert key_wait_of(app) > 0.0
    drawn[0] = time.monotonic()  # drawn
    assert key_wait_of(app) <= 0.0


async def test_the_figures_watch_the_apps_frames() -> None:
    box = Box(Keys())
    async with BoxHost(box).run_test() as pilot:
        box.exact.ask(1)
        await wait_until(pilot, lambda: box.results, "the result")
        drawn = exact_figures._DRAWN[pilot.app]
        before = drawn[0]
        box.refresh()
        await wait_until(pilot, lambda: drawn[0] > before, "a frame noted")


async def test_the_scoreboard_computes_off_the_event_loop(monkeypatch) -> None:
    release = threading.Event()
    figures = Session.agent_figures
    asked: list[str] = []

    def slow(session: Session, snapshot=None):
        asked.append(threading.current_thread().name)
        release.wait(DEADLINE)
        return figures(session, snapshot)

    monkeypatch.setattr(Session, "agent_figures", slow)
    session = Session("frozenlake", seed=0)
    app = PlayHost(session)
    try:
        async with app.run_test(size=VIEW_SIZE) as pilot:
            view = app.play_view
            await wait_until(pilot, lambda: asked, "the figures asked for")
            steps = view.game.last.steps
            await pilot.press("right")  # the key takes effect while they are computed
            assert view.game.last.steps == steps + 1
            assert not release.is_set() and not view.agent_figures_shown
            assert "being computed" in view.query_one("#play-scoreboard").text(compact=False)
            release.set()
            await wait_until(pilot, lambda: view.agent_figures_shown, "the figures")
            assert view.agent_figures == figures(session)
            assert threading.main_thread().name not in asked
    finally:
        release.set()


async def test_a_snapshot_waits_while_a_key_is_answered_during_training() -> None:
    app = TrainHost(Session("frozenlake", seed=0, hp=QLearning.hyperparameters(episodes=10**9)))
    async with app.run_test(size=(120, 40)) as pilot:
        view, runner = app.train_view, app.runner
        assert runner.start()
        try:
            shown = view._version
            await wait_until(pilot, lambda: runner.latest.version != shown, "a new snapshot")
            app._key_since = time.monotonic() + DEADLINE  # a key being answered
            view.show_snapshot(runner.latest, runner)
            assert view._version == shown  # its frame first
            app._key_since = 0.0  # drawn
            latest = runner.latest
            view.show_snapshot(latest, runner)
            assert view._version == latest.version
        finally:
            runner.pause()


async def test_a_snapshot_held_back_by_a_key_as_training_pauses_is_shown_after(
    monkeypatch,
) -> None:
    """The last snapshot before a pause, held back while the pause key was answered, is
    the one the view ends on (it stayed on an older one: the app's timer offered a
    snapshot it had already offered only while training ran)."""
    hp = QLearning.hyperparameters(episodes=10**9)
    app = TuiGymApp(Session("frozenlake", seed=0, hp=hp))
    async with app.run_test(size=(120, 40)) as pilot:
        view, runner = await open_train(pilot), app.runner
        assert runner.start()
        shown = view.shown_version
        await wait_until(pilot, lambda: runner.latest.version != shown, "a new snapshot")
        # No await from here on: the app's own timer stays out of it.
        runner.pause()
        assert runner.wait_idle(DEADLINE)
        latest = runner.latest
        assert view.shown_version != latest.version
        with monkeypatch.context() as still:  # the tick that saw it while training ran
            still.setattr(type(runner), "running", property(lambda self: True))
            app._key_since = time.monotonic() + DEADLINE  # the pause key being answered
            app._tick()
        assert view.shown_version != latest.version  # held back
        app._key_since = 0.0  # its frame drawn
        app._tick()
        assert view.shown_version == latest.version


async def test_the_persons_record_shows_at_once_while_the_agents_figures_compute(
    monkeypatch,
) -> None:
    release = threading.Event()
    figures = Session.agent_figures

    def slow(session: Session, snapshot=None):
        release.wait(DEADLINE)
        return figures(session, snapshot)

    monkeypatch.setattr(Session, "agent_figures", slow)
    app = PlayHost(Session("blackjack", seed=0))
    try:
        async with app.run_test(size=VIEW_SIZE) as pilot:
            view = app.play_view
            board = view.query_one("#play-scoreboard")
            assert "no hands played yet" in board.text(compact=False)
            await pilot.press("s")  # stick: the hand is over
            assert view.game.done and not release.is_set()
            text = board.text(compact=False)
            assert "no hands played yet" not in text and "over 1 hand" in text
            assert "being computed" in text
    finally:
        release.set()
