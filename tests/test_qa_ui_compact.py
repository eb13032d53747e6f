"""At 80x24: a Taxi replay keeps the city's wall all round; the map editor reaches every
column of a wide map and keeps its cursor in sight; a burst of resize keys leaves one
notice, not a stack of them."""

from __future__ import annotations

from pathlib import Path

from tests.board_support import rows
from tests.test_ui_replay import ReplayHost, record
from tui_gym.core.recording import read_recording
from tui_gym.ui.replay_screen import ReplayScreen

COMPACT = (80, 24)


async def test_a_taxi_replay_at_80x24_draws_the_wall_round_the_city(tmp_path: Path) -> None:
    recording = read_recording(record(tmp_path / "taxi.jsonl", "taxi", 1, moves=3))
    host = ReplayHost(recording)
    async with host.run_test(size=COMPACT) as pilot:
        await pilot.pause()
        screen = host.screen
        assert isinstance(screen, ReplayScreen) and screen.board is not None
        lines = [line.strip() for line in rows(screen.board) if line.strip()]
        assert lines[0].startswith("┏") and lines[0].endswith("┓")
        bottom = next(line for line in lines if line.startswith("┗"))
        assert bottom.endswith("┛")
        assert sum(line.startswith("┃") and line.endswith("┃") for line in lines) >= 5
