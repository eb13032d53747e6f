"""`TaxiBoard` mounted alone: the city drawn from Taxi's own map, fitted, driven by keys and
clicks, and what each action did said in words."""

from __future__ import annotations

from gymnasium.envs.toy_text.taxi import MAP
from textual.binding import Binding
from textual.geometry import Offset

from tests.board_support import (
    PLAY_BIG,
    PLAY_COMPACT,
    TRAIN_BIG,
    TRAIN_COMPACT,
    BoardApp,
    char_at,
    rows,
    screen_height,
    style_at,
    text_of,
)
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.widgets.board_drawing import MapLayout
from tui_gym.ui.widgets.taxi_board import TaxiBoard

TAXI_MAP = [
    "+---------+",
    "|R: | : :G|",
    "| : | : : |",
    "| : : : : |",
    "| | : | : |",
    "|Y| : |B: |",
    "+---------+",
]


def walls_of(lines: list[str]) -> list[list[int]]:
    """[row, col] of every cell with a wall on its east side ('|' between two cells)."""
    inner = lines[1:-1]
    cols = (len(inner[0]) - 1) // 2
    return [
        [r, c] for r, line in enumerate(inner) for c in range(cols - 1) if line[2 * c + 2] == "|"
    ]


def stands_of(lines: list[str]) -> tuple[list[list[int]], list[str]]:
    found = [
        ([r, c], line[2 * c + 1])
        for r, line in enumerate(lines[1:-1])
        for c in range((len(line) - 1) // 2)
        if line[2 * c + 1].isalpha()
    ]
    return [cell for cell, _ in found], [name for _, name in found]


STANDS, NAMES = stands_of(TAXI_MAP)
WALLS = walls_of(TAXI_MAP)


def city(**scene):
    base = {
        "taxi": (2, 2),
        "passenger": 2,
        "destination": 1,
        "stands": STANDS,
        "stand_names": NAMES,
        "walls": WALLS,
        "last_action": None,
        "last_illegal": False,
        "rainy": False,
    }
    return {**base, **scene}


def layout(board: TaxiBoard) -> MapLayout:
    drawn = board.layout_drawn
    assert drawn is not None
    return drawn


def corner(board: TaxiBoard, cell: tuple[int, int], dx: int = 0, dy: int = 0) -> Offset:
    """The canvas offset of a tile's top-left character, moved by (dx, dy)."""
    drawn = layout(board)
    shape = drawn.shape
    return Offset(drawn.left + shape.x_of(cell[1]) + dx, drawn.top + shape.y_of(cell[0]) + dy)


def middle_line(board: TaxiBoard, cell: tuple[int, int]) -> str:
    drawn = layout(board)
    spot = drawn.cell_center(cell)
    x0 = drawn.left + drawn.shape.x_of(cell[1])
    return rows(board)[spot.y][x0 : x0 + drawn.shape.cell_w]


def test_the_test_map_is_taxis_own() -> None:
    assert TAXI_MAP == MAP
    assert WALLS == [[0, 1], [1, 1], [3, 0], [3, 2], [4, 0], [4, 2]]
    assert STANDS == [[0, 0], [0, 4], [4, 0], [4, 3]] and NAMES == ["R", "G", "Y", "B"]


# --- drawing -----------------------------------------------------------------------


async def test_walls_stands_passenger_destination_and_cab_are_drawn() -> None:
    board = TaxiBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(city())
        await pilot.pause()
        shape = layout(board).shape
        assert (shape.cell_w, shape.cell_h, shape.frame) == (11, 4, True)
        w = shape.cell_w
        for r in range(5):
            for c in range(4):
                wall = "┃" if [r, c] in WALLS else "┆"
                assert all(char_at(board, corner(board, (r, c), w, k)) == wall for k in range(4))
        for (r, c), name in zip(STANDS, NAMES, strict=True):
            assert char_at(board, corner(board, (r, c))) == name
            dest = "◎" if name == "G" else " "
            assert char_at(board, corner(board, (r, c), w - 1)) == dest
        assert char_at(board, layout(board).cell_center((4, 0))) == "☺"
        assert "TAXI" in middle_line(board, (2, 2)) and "☺" not in middle_line(board, (2, 2))
        assert char_at(board, corner(board, (0, 0), -1, -1)) == "┏"
        assert "Passenger waiting at Y, going to G" in text_of(board)
        colours = {style_at(board, corner(board, tuple(cell), 1, 1)).bgcolor for cell in STANDS}
        assert len(colours) == 4


async def test_the_passenger_aboard_changes_the_cab() -> None:
    boards = [(TaxiBoard(), PLAY_BIG), (TaxiBoard(interactive=False), TRAIN_COMPACT)]
    app = BoardApp(boards)
    async with app.run_test(size=(80, screen_height(boards))) as pilot:
        big, small = (board for board, _ in boards)
        empty = {}
        for board in (big, small):
            board.show_scene(city(taxi=(4, 0)))
        await pilot.pause()
        for board in (big, small):
            empty[board] = style_at(board, layout(board).cell_center((4, 0))).bgcolor
            board.show_scene(city(taxi=(4, 0), passenger=4, last_action="pickup"))
        await pilot.pause()
        assert "TAXI☺" in middle_line(big, (4, 0))
        assert "T☺" in middle_line(small, (4, 0))
        for board in (big, small):
            full = style_at(board, layout(board).cell_center((4, 0))).bgcolor
            assert full != empty[board]
        assert big.aboard and "Picked the passenger up: now to G" in text_of(big)


async def test_the_city_fits_the_compact_sizes() -> None:
    boards = [
        (TaxiBoard(), PLAY_COMPACT),
        (TaxiBoard(interactive=False), TRAIN_BIG),
        (TaxiBoard(interactive=False), TRAIN_COMPACT),
    ]
    app = BoardApp(boards)
    async with app.run_test(size=(80, screen_height(boards))) as pilot:
        for board, _ in boards:
            board.show_scene(city(taxi=(1, 3)))
        await pilot.pause()
        for board, _ in boards:
            width, height = board.canvas.content_size
            drawing = rows(board)
            assert len(drawing) <= height and max(len(line) for line in drawing) <= width
            assert char_at(board, layout(board).cell_center((1, 3))) == "T"
            assert char_at(board, layout(board).cell_center((4, 0))) == "☺"
            assert "☺ at Y → G" in text_of(board) or "waiting at Y, going to G" in text_of(board)


# --- words -----------------------------------------------------------------------


async def test_what_each_action_did_is_said() -> None:
    board = TaxiBoard(interactive=False)
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:

        def after(before: dict, **now) -> str:
            board.start_episode()
            board.show_scene(before)
            board.show_scene({**before, **now})
            return board.event_text

        at_y = city(taxi=(4, 0))
        aboard = city(taxi=(2, 2), passenger=4)
        assert after(city(), last_action="pickup", last_illegal=True) == (
            "Illegal pickup (−10): the passenger is not here"
        )
        assert after(aboard, last_action="pickup", last_illegal=True) == (
            "Illegal pickup (−10): already aboard"
        )
        assert after(city(), last_action="dropoff", last_illegal=True) == (
            "Illegal drop-off (−10): no passenger aboard"
        )
        assert after(aboard, last_action="dropoff", last_illegal=True) == (
            "Illegal drop-off (−10): drop off at a stand"
        )
        await pilot.pause()
        assert "Illegal drop-off (−10): drop off at a stand" in text_of(board)
        assert after(city(taxi=(0, 4), passenger=4), passenger=1, last_action="dropoff") == (
            "Passenger delivered to G!"
        )
        assert after({**at_y, "passenger": 4}, passenger=2, last_action="dropoff") == (
            "Dropped the passenger at Y, not G"
        )
        assert after(city(taxi=(0, 1)), last_action="east") == "A wall blocks the way east"
        assert after(city(taxi=(0, 2)), last_action="north") == (
            "The edge of the city blocks the way north"
        )
        assert after(city(), taxi=(1, 2), last_action="north") == "Drove north"
        rainy = city(rainy=True)
        assert after(rainy, taxi=(2, 3), last_action="south") == (
            "The rain pushed the cab: asked south, went east"
        )
        assert after(aboard, taxi=(2, 1), destination=3, last_action="west") == (
            "The passenger changed their mind: now to B"
        )
        await pilot.pause()
        assert board.border_title == "Taxi"
        board.show_scene(rainy)
        await pilot.pause()
        assert board.border_title == "Taxi · rain" and "╱" in text_of(board)


# --- keys and clicks -----------------------------------------------------------------


def test_the_keys_leave_the_apps_own_keys_alone() -> None:
    taxi = {binding.key for binding in Binding.make_bindings(TaxiBoard.BINDINGS)}
    app_keys = {binding.key for binding in Binding.make_bindings(TuiGymApp.BINDINGS)}
    view_keys = {binding.key for binding in Binding.make_bindings(PlayView.BINDINGS)}
    assert "p" not in taxi and {"k", "l", "o"} <= taxi
    # WASD as on the GridWorld board; n starts a new episode on every board, over the
    # app's one training step, while the board has the focus.
    assert taxi & (app_keys | view_keys) <= {"w", "a", "n"}


async def test_keys_post_taxi_actions_by_name() -> None:
    board = TaxiBoard()
    app = BoardApp([(board, PLAY_COMPACT)])
    async with app.run_test(size=(60, 20)) as pilot:
        board.show_scene(city())
        board.focus()
        await pilot.press("up", "w", "down", "s", "left", "a", "right", "d", "k", "l", "o")
        await pilot.press("enter", "n", "r")  # a stray Enter mid-episode loses nothing
        board.set_episode_over(True)
        await pilot.press("enter")
        await pilot.pause()
        moves = ["north", "north", "south", "south", "west", "west", "east", "east"]
        acts = [("act", name) for name in [*moves, "pickup", "dropoff", "dropoff"]]
        assert app.posted == [*acts, ("new",), ("new",), ("new",)]
        help_keys = [key for key, _ in board.key_help()]
        assert "k" in help_keys and "l / o" in help_keys


async def test_clicks_drive_towards_a_cell_and_the_cab_picks_up() -> None:
    board = TaxiBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(city())
        await pilot.pause()
        for cell in ((1, 2), (2, 3), (4, 2), (2, 0), (2, 2)):
            await pilot.click(board.canvas, offset=layout(board).cell_center(cell))
        await pilot.click(board.canvas, offset=corner(board, (2, 1), layout(board).shape.cell_w))
        board.show_scene(city(passenger=4))
        await pilot.pause()
        await pilot.click(board.canvas, offset=layout(board).cell_center((2, 2)))
        await pilot.pause()
        acts = [name for _, name in app.posted]
        assert acts == ["north", "east", "south", "west", "pickup", "dropoff"]  # lane: nothing
