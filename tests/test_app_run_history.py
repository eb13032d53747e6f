"""Runs trained in the app, kept in the run history: `SessionRunLog`, and the app through pilot."""

from __future__ import annotations

import time
from pathlib import Path

from tui_gym.algorithms import QLearning
from tui_gym.core.experiments import RunHistory, RunKind, RunStatus
from tui_gym.session.experiments.app_recording import SessionRunLog
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp

from .waiting import wait_for

DEADLINE = 20.0


class Clock:
    """A clock the test moves by hand, so that flushes happen when the test says."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def blackjack(episodes: int = 100_000) -> Session:
    return Session("blackjack", seed=0, hp=QLearning.hyperparameters(episodes=episodes))


def test_a_run_lasts_from_the_first_episode_to_a_reset_or_the_end(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    clock = Clock()
    log = SessionRunLog(db, clock=clock)
    session = blackjack()
    assert log.observe(session, session.trainer.latest) is None  # nothing trained: no run
    session.trainer.run(episodes=3000)
    clock.now = 10.0
    assert log.observe(session, session.trainer.latest) is None
    session.trainer.run(episodes=2000)
    clock.now = 20.0
    log.observe(session, session.trainer.latest)  # a flush of the open run
    session.reset_agent()  # ends the first run
    log.observe(session, session.trainer.latest)
    session.trainer.run(episodes=1000)
    log.observe(session, session.trainer.latest)
    log.close(wait=None)  # ends the second run; every write landed

    with RunHistory(db) as history:
        second, first = history.list_runs()
        assert (first.kind, first.status, second.status) == (
            RunKind.APP, RunStatus.FINISHED, RunStatus.FINISHED)
        record = history.get_run(first.id)
        returns = record.curve("return")
        assert returns is not None and returns.episodes[-1] <= 5000
        assert returns.episodes[-1] > 4000
        assert record.hyperparameters["episodes"] == 100_000
        assert record.curve("exact_value") is not None
        assert {"mean_return_last", "exact_value", "exact_gap"} <= {f.name for f in first.figures}
        later = history.get_run(second.id).curve("return")
        assert later is not None and later.episodes[-1] <= 1000


def test_training_again_after_a_switch_back_is_a_new_run_of_the_new_episodes(
    tmp_path: Path,
) -> None:
    db = tmp_path / "runs.db"
    log = SessionRunLog(db, clock=Clock())
    blackjack_session, other = blackjack(), Session("gridworld", seed=0)
    log.observe(blackjack_session, blackjack_session.trainer.latest)
    blackjack_session.trainer.run(episodes=4096)
    log.observe(blackjack_session, blackjack_session.trainer.latest)
    log.observe(other, other.trainer.latest)  # a switch ends the Blackjack run
    log.observe(blackjack_session, blackjack_session.trainer.latest)  # back: nothing new yet
    blackjack_session.trainer.run(episodes=4096)
    log.observe(blackjack_session, blackjack_session.trainer.latest)
    log.close(wait=None)
    with RunHistory(db) as history:
        later, first = history.list_runs()
        assert history.get_run(first.id).curve("return").episodes[-1] == 4096
        episodes = history.get_run(later.id).curve("return").episodes
        assert episodes[0] > 4096 and episodes[-1] == 8192


def first_notice(log: SessionRunLog, session: Session) -> str:
    """Train a little and follow it until the log has a line to show."""
    log.observe(session, session.trainer.latest)
    session.trainer.run(episodes=500)
    deadline = time.monotonic() + DEADLINE
    while time.monotonic() < deadline:
        notice = log.observe(session, session.trainer.latest)
        if notice:
            return notice
        assert log._writer is not None
        log._writer.join(0.05)  # the writer thread opens the file
    raise AssertionError("no notice")


def test_a_history_that_cannot_be_opened_is_one_notice(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    db.write_text("not a database\n" * 100)
    before = db.read_bytes()
    log = SessionRunLog(db, clock=Clock())
    session = blackjack()
    notice = first_notice(log, session)
    assert "not a tui-gym run history" in notice
    session.trainer.run(episodes=500)
    assert log.observe(session, session.trainer.latest) is None  # said once
    log.close(wait=None)
    assert db.read_bytes() == before


async def test_the_app_records_the_run_it_trains(tmp_path: Path) -> None:
    db = tmp_path / "runs.db"
    app = TuiGymApp(blackjack(episodes=2000), runner="thread",
                    run_log=SessionRunLog(db, clock=Clock()))
    async with app.run_test(size=(80, 24)) as pilot:
        await pilot.press("t", "space")
        await wait_for(pilot, lambda: app.runner.finished
                       and app._last_version == app.runner.latest.version,
                       "training to finish", DEADLINE)
        await pilot.press("q")
    with RunHistory(db) as history:
        [run] = history.list_runs()
        assert (run.kind, run.game, run.status) == (RunKind.APP, "blackjack", RunStatus.FINISHED)
        returns = history.get_run(run.id).curve("return")
        assert returns is not None and returns.episodes[-1] == 2000


def test_a_run_records_the_settings_it_trained_with_its_episodes_and_its_save(
    tmp_path: Path,
) -> None:
    from tui_gym.ui.compare_series import row_of_record

    db = tmp_path / "runs.db"
    clock = Clock()
    log = SessionRunLog(db, clock=clock)
    session = blackjack(episodes=200_000)
    log.observe(session, session.trainer.latest)
    session.trainer.run(episodes=3000)
    log.observe(session, session.trainer.latest)  # the run starts with the settings of then
    session.set_hyperparameters({"episodes": 400_000, "epsilon_decay_fraction": 0.25})
    session.trainer.run(episodes=2000)
    clock.now = 10.0
    log.observe(session, session.trainer.latest)
    saved = session.save(tmp_path / "bj.tgym")
    log.saved(session, saved)
    session.trainer.run(episodes=1001)
    log.observe(session, session.trainer.latest)
    log.close(wait=None)
    with RunHistory(db) as history:
        [run] = history.list_runs()
        record = history.get_run(run.id)
    assert record.hyperparameters["episodes"] == 400_000
    assert record.hyperparameters["epsilon_decay_fraction"] == 0.25
    assert record.agent_path == str(saved.resolve())
    episodes = run.figure("episodes")
    assert episodes is not None and episodes.value == 6001
    assert row_of_record(record).episodes == 6001  # the table says what ran, not a bucket's end
    returns = record.curve("return")
    assert returns is not None and returns.episodes[-1] < 6001


def test_a_history_path_that_cannot_be_examined_is_one_notice(tmp_path: Path) -> None:
    log = SessionRunLog(tmp_path / ("x" * 300) / "runs.db", clock=Clock())
    session = blackjack()
    notice = first_notice(log, session)
    assert "cannot be examined (File name too long)" in notice
    assert "\n" not in notice and len(notice) < 300
    assert log._writer is not None and log._writer.is_alive()  # it waits for work: no crash
    session.trainer.run(episodes=500)
    assert log.observe(session, session.trainer.latest) is None
    log.close(wait=None)


async def test_the_app_goes_on_without_a_history_it_cannot_examine(tmp_path: Path) -> None:
    db = tmp_path / ("x" * 300) / "runs.db"
    app = TuiGymApp(blackjack(episodes=2000), runner="thread", run_log=SessionRunLog(db),
                    db=str(db))
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.press("t", "space")
        await wait_for(pilot, lambda: app.runner.finished, "training to finish", DEADLINE)
        await pilot.press("v")
        await wait_for(pilot, lambda: app.compare_view is not None
                       and app.compare_view.history_error is not None,
                       "the Compare view's message", DEADLINE)
        assert app.compare_view is not None and "cannot be examined" in app.compare_view.message
        await pilot.press("q")
    assert app.return_code == 0 and app.thread_crash is None
