"""`tui-gym --no-history` keeps nothing: the Compare view compares into a scratch file
that goes with the app, and says so."""

from __future__ import annotations

from pathlib import Path

from textual.app import App, ComposeResult

from tui_gym.core.experiments import RunHistory, RunRecorder, RunSpec
from tui_gym.session.session import Session
from tui_gym.ui.app import history_for_app
from tui_gym.ui.compare_view import CompareView


def test_a_kept_history_is_the_file_asked_for(tmp_path: Path) -> None:
    with history_for_app(str(tmp_path / "runs.db"), keep_history=True) as db:
        assert db == str(tmp_path / "runs.db")
    with history_for_app(None, keep_history=True) as db:
        assert db is None  # the default file, resolved where it is read


def test_without_history_the_compare_file_goes_with_the_app(tmp_path: Path) -> None:
    with history_for_app(str(tmp_path / "runs.db"), keep_history=False) as db:
        assert db is not None and Path(db).parent != tmp_path
        with RunHistory(db) as history, RunRecorder(
            history, RunSpec("compare", "blackjack", "q-learning", seeds=range(2))
        ):
            pass
        assert Path(db).exists()
    assert not Path(db).parent.exists()
    assert list(tmp_path.iterdir()) == []


class ScratchApp(App[None]):
    def __init__(self, db: Path) -> None:
        super().__init__()
        self.session = Session("blackjack", seed=0)
        self.db = db

    def compose(self) -> ComposeResult:
        yield CompareView(db=self.db, kept=False)


async def test_the_compare_view_says_nothing_is_kept(tmp_path: Path) -> None:
    app = ScratchApp(tmp_path / "runs.db")
    async with app.run_test(size=(100, 40)) as pilot:
        await pilot.pause()
        view = app.query_one(CompareView)
        assert view.message.startswith("No comparisons of Blackjack yet (--no-history: "
                                       "they are shown until the app ends, and not kept)")
        assert "runs.db" not in view.message
