"""At 80x24: a Taxi replay keeps the city's wall all round; the map editor reaches every
column of a wide map and keeps its cursor in sight; a burst of resize keys leaves one
notice, not a stack of them."""

from __future__ import annotations

from pathlib import Path

from textual.app import App, ComposeResult
from textual.containers import VerticalScroll
from textual.geometry import Region
from textual.widgets._toast import Toast

from tests.board_support import rows
from tests.test_ui_map_editor import editing
from tests.test_ui_replay import ReplayHost, record
from tests.waiting import wait_for
from tui_gym.core.recording import read_recording
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.map_editing import show_optimum
from tui_gym.ui.replay_screen import ReplayScreen
from tui_gym.ui.widgets.map_editor import MapEditor

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


class EditorHost(App[None]):
    """A map editor in a box smaller than the map, as in the compact Train view."""

    CSS = "VerticalScroll { width: 44; height: 14; }"

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session

    def compose(self) -> ComposeResult:
        with VerticalScroll():
            yield MapEditor()

    def on_mount(self) -> None:
        editor = self.query_one(MapEditor)
        game, kwargs = self.session.game, self.session.env_kwargs
        editor.start(game.grid_map(kwargs), game.map_tools)
        show_optimum(editor, self.session, None)
        editor.focus_canvas()


def in_sight(editor: MapEditor, cell: tuple[int, int]) -> bool:
    """Whether `cell` of the map is drawn inside the editor and its scrolling box."""
    canvas = editor.canvas
    hit = next((x, y) for y in range(canvas.size.height) for x in range(canvas.size.width)
               if canvas.cell_at(x, y) == (0, *cell))
    place = Region(canvas.content_region.x + hit[0], canvas.content_region.y + hit[1], 1, 1)
    box = editor.app.query_one(VerticalScroll).region
    return place in editor.content_region and place in box


async def test_the_cursor_reaches_every_cell_of_a_map_wider_and_taller_than_the_editor(
) -> None:
    cells = "\n".join(["F" * 16] * 9 + ["S" + "F" * 14 + "G"])
    session = Session("cliffwalking", env_kwargs={"layout": cells}, seed=0)
    host = EditorHost(session)
    async with host.run_test(size=(60, 20)) as pilot:
        await pilot.pause()
        editor = host.query_one(MapEditor)
        assert editor.cursor == (0, 0) and in_sight(editor, (0, 0))
        for _ in range(15):
            await pilot.press("right")
            await pilot.pause()  # drawn: the regions `in_sight` reads are the new ones
            assert in_sight(editor, editor.cursor)
        for _ in range(9):
            await pilot.press("down")
            await pilot.pause()
            assert in_sight(editor, editor.cursor)
        assert editor.cursor == (9, 15)
        for _ in range(15):
            await pilot.press("left")
        await pilot.pause()
        assert editor.cursor == (9, 0) and in_sight(editor, (9, 0))


async def test_a_burst_of_resize_keys_leaves_one_notice() -> None:
    session = Session("cliffwalking", env_kwargs={"layout": "SFF\nFFG\n"}, seed=0)
    app = TuiGymApp(session)
    async with app.run_test(size=COMPACT, notifications=True) as pilot:
        await pilot.press("m")
        await wait_for(pilot, lambda: editing(app.train_view), "the editor")
        await pilot.press(*["shift+right"] * 5)
        await wait_for(pilot, lambda: app.session.game.cells(app.session.env_kwargs)[0]
                       == "SFFFFFFF", "the map 8 wide")
        await pilot.pause()
        said = [n.message for n in app._notifications]
        assert said.count("Observations changed meaning, so the agent was reset.") == 1
        assert len(app.screen.query(Toast)) == 1
