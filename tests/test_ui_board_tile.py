"""`TileBoard` mounted alone: lakes, the cliff and plain maps drawn, fitted, played by keys
and clicks, and the last move said in words."""

from __future__ import annotations

import pytest
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
from tui_gym.ui.widgets.board_drawing import MapLayout, MapShape
from tui_gym.ui.widgets.tile_board import TileBoard, choose_shape

LAKE4 = ["SFFF", "FHFH", "FFFH", "HFFG"]
LAKE8 = [
    "SFFFFFFF",
    "FFFFFFFF",
    "FFFHFFFF",
    "FFFFFHFF",
    "FFFHFFFF",
    "FHHFFFHF",
    "FHFFHFHF",
    "FFFHFFFG",
]
LAKE12 = [
    "".join("H" if (5 * r + 3 * c) % 11 == 0 and r + c else "F" for c in range(12))
    for r in range(12)
]
LAKE12 = ["S" + LAKE12[0][1:], *LAKE12[1:11], LAKE12[11][:11] + "G"]
CLIFF = ["F" * 12] * 3 + ["S" + "C" * 10 + "G"]
MAZE = ["SFWF", "FRWF", "FFHG"]

# The drawing area inside each board size (the border and the button row taken off).
CANVAS = {PLAY_BIG: (72, 23), PLAY_COMPACT: (44, 9), TRAIN_BIG: (36, 7), TRAIN_COMPACT: (24, 7)}


def lake(cells=LAKE4, **scene):
    return {"cells": cells, "theme": "lake", "agent": (0, 0), "last_action": None, **scene}


def layout(board: TileBoard) -> MapLayout:
    drawn = board.layout_drawn
    assert drawn is not None
    return drawn


def centre(board: TileBoard, cell: tuple[int, int]) -> str:
    return char_at(board, layout(board).cell_center(cell))


def tile_line(board: TileBoard, cell: tuple[int, int]) -> str:
    """The characters of a tile's middle line."""
    drawn = layout(board)
    middle = drawn.cell_center(cell)
    x0 = drawn.left + drawn.shape.x_of(cell[1])
    return rows(board)[middle.y][x0 : x0 + drawn.shape.cell_w]


# --- drawing -----------------------------------------------------------------------


async def test_every_kind_of_tile_has_its_glyph_and_colour() -> None:
    board = TileBoard(interactive=False)
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(lake(agent=(0, 1)))
        await pilot.pause()
        assert layout(board).shape.cell_w == 11  # the 4x4 lake drawn large
        expected = {"S": "⌂", "F": "·", "H": "○", "G": "★"}
        for r, row in enumerate(LAKE4):
            for c, kind in enumerate(row):
                want = "●" if (r, c) == (0, 1) else expected[kind]
                assert centre(board, (r, c)) == want, (r, c)
        backgrounds = {
            name: style_at(board, layout(board).cell_center(cell)).bgcolor
            for name, cell in (("hole", (1, 1)), ("goal", (3, 3)), ("agent", (0, 1)))
        }
        ice = style_at(board, layout(board).cell_center((0, 2)) + Offset(2, 0)).bgcolor
        assert len({ice, *backgrounds.values()}) == 4
        text = text_of(board)
        for word in ("start", "ice", "hole", "goal", "agent", "0", "3"):
            assert word in text

        board.start_episode()
        rewards = {f"3,{c}": -100 for c in range(1, 11)}
        board.show_scene({"cells": CLIFF, "theme": "cliff", "agent": (3, 0), "rewards": rewards})
        await pilot.pause()
        assert board.border_title == "Cliff"
        assert all(centre(board, (3, c)) == "▒" for c in range(1, 11))
        assert centre(board, (3, 11)) == "★" and centre(board, (3, 0)) == "●"
        assert layout(board).shape.cell_h >= 2 and "−100" in text_of(board)
        assert "ground" in text_of(board) and "cliff" in text_of(board)

        board.start_episode()
        board.show_scene(
            {"cells": MAZE, "theme": "plain", "agent": (2, 0), "rewards": {"1,1": 5, "2,2": -10}}
        )
        await pilot.pause()
        assert centre(board, (0, 2)) == "█" and centre(board, (2, 2)) == "○"
        assert "+5" in tile_line(board, (1, 1))
        assert "−10" in text_of(board) and "pit" in text_of(board)


async def test_marks_and_slip_overlay_the_tiles() -> None:
    board = TileBoard(interactive=False)
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(lake(agent=(3, 0), marks={"0,1": "→", "2,2": "0.5"}, slip={"0,3": 1 / 3}))
        await pilot.pause()
        assert centre(board, (0, 1)) == "→"
        assert "0.5" in tile_line(board, (2, 2))
        drawn = layout(board)
        corner = Offset(drawn.left + drawn.shape.x_of(4) - 1, drawn.top)
        assert char_at(board, corner) == "≈"
        assert centre(board, (3, 0)) == "●"  # the agent in a hole: drawn on top ...
        assert "fell through the ice" in text_of(board)  # ... and said


def test_the_largest_drawing_that_fits_is_chosen() -> None:
    for cells in (LAKE4, LAKE8, LAKE12, CLIFF):
        for size in (PLAY_BIG, PLAY_COMPACT, TRAIN_BIG, TRAIN_COMPACT):
            width, height = CANVAS[size]
            shape = choose_shape(len(cells), len(cells[0]), width, height)
            assert shape.width <= width and shape.height + 1 <= height, (len(cells), size)
            bigger = MapShape(shape.rows, shape.cols, shape.cell_w + 2, shape.cell_h + 1)
            assert bigger.width > width or bigger.height + 1 > height
    assert choose_shape(4, 4, *CANVAS[PLAY_BIG]) == MapShape(4, 4, 11, 5, axes=True)
    assert choose_shape(12, 12, *CANVAS[PLAY_BIG]) == MapShape(12, 12, 3, 1, axes=True)
    assert not choose_shape(8, 8, *CANVAS[PLAY_COMPACT]).half  # glyphs at 80x24
    assert choose_shape(12, 12, *CANVAS[PLAY_COMPACT]).half  # only colours fit


@pytest.mark.parametrize("cells", [LAKE4, LAKE12], ids=["4x4", "12x12"])
async def test_small_and_large_maps_fit_the_compact_sizes(cells: list[str]) -> None:
    n = len(cells)
    agent = (n - 2, 1)
    boards = [
        (TileBoard(), PLAY_COMPACT),
        (TileBoard(interactive=False), TRAIN_BIG),
        (TileBoard(interactive=False), TRAIN_COMPACT),
    ]
    app = BoardApp(boards)
    async with app.run_test(size=(80, screen_height(boards))) as pilot:
        for board, _ in boards:
            board.show_scene(lake(cells, agent=agent))
        await pilot.pause()
        for board, size in boards:
            assert board.canvas.content_size == CANVAS[size]
            width, height = CANVAS[size]
            drawing = rows(board)
            assert len(drawing) <= height and max(len(line) for line in drawing) <= width
            drawn = layout(board)
            spot = drawn.cell_center(agent)
            if drawn.shape.half:  # colour only: the agent's half of the cell is the agent's colour
                agent_colour = board.get_component_rich_style("tile--agent").bgcolor
                half = style_at(board, spot)
                assert (half.color if agent[0] % 2 == 0 else half.bgcolor) == agent_colour
            else:
                assert char_at(board, spot) == "●"
            said = "\n".join(drawing)
            assert f"at row {agent[0]}, column 1" in said or f"at ({agent[0]}, 1)" in said


async def test_tiles_keep_their_size_while_the_space_changes_by_a_line() -> None:
    board = TileBoard()
    app = BoardApp([(board, PLAY_COMPACT)])
    async with app.run_test(size=(60, 20)) as pilot:
        board.show_scene(lake())
        await pilot.pause()
        first = layout(board).shape
        assert (first.cell_w, first.cell_h) == (5, 2)
        board.styles.height = PLAY_COMPACT[1] + 4  # room now for larger tiles
        board.show_scene(lake(agent=(0, 1), last_action="right"))
        await pilot.pause()
        assert layout(board).shape == first  # mid-episode: the same tiles
        board.start_episode()
        board.show_scene(lake())
        await pilot.pause()
        assert layout(board).shape.cell_w > first.cell_w  # a new episode takes the room
        board.styles.height = PLAY_COMPACT[1]
        await pilot.pause()
        assert layout(board).shape == first  # too big now: a smaller one at once


# --- words -----------------------------------------------------------------------


async def test_the_last_move_is_said_slips_falls_and_the_goal() -> None:
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(lake(agent=(0, 0)))
        board.show_scene(lake(agent=(1, 0), last_action="right", slipped=True))
        await pilot.pause()
        assert board.event_text == "You slipped on the ice: asked right, went down"
        assert board.event_text in text_of(board)
        board.show_scene(lake(agent=(1, 0), last_action="left"))
        assert board.event_text == "You bumped into the edge (asked left)"
        board.show_scene(lake(agent=(2, 0), last_action="down"))
        assert board.event_text == "You moved down"
        board.show_scene(lake(agent=(3, 0), last_action="down", slipped=True))
        assert board.event_text == "You slipped on the ice into a hole"

        board.start_episode()
        board.show_scene(lake(agent=(3, 2)))
        board.show_scene(lake(agent=(3, 3), last_action="right"))
        assert board.event_text == "You reached the goal"

        cliff = {"cells": CLIFF, "theme": "cliff", "agent": (2, 3)}
        board.start_episode()
        board.show_scene(cliff)
        board.show_scene({**cliff, "agent": (3, 0), "last_action": "down"})
        await pilot.pause()
        assert board.event_text == "You fell off the cliff: back to the start"
        assert board.event_text in text_of(board)
        board.show_scene({**cliff, "agent": (3, 0), "last_action": "right"})
        assert board.event_text == "You fell off the cliff: back to the start"
        board.set_agent_playing(True)
        await pilot.pause()
        assert "Agent fell off the cliff" in text_of(board)


async def test_a_long_caption_is_shortened_to_fit() -> None:
    board = TileBoard(interactive=False)
    app = BoardApp([(board, TRAIN_COMPACT)])
    async with app.run_test(size=(40, 10)) as pilot:
        board.show_scene(lake(agent=(0, 0)))
        board.show_scene(lake(agent=(1, 0), last_action="right", slipped=True))
        await pilot.pause()
        assert "Slipped: right → down" in text_of(board)


async def test_the_trail_shows_the_moves_that_left_each_cell() -> None:
    board = TileBoard(interactive=False)
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        for cell in ((0, 0), (0, 1), (0, 2), (1, 2), (2, 2)):
            board.show_scene(lake(agent=cell))
        await pilot.pause()
        assert [centre(board, c) for c in ((0, 0), (0, 1), (0, 2), (1, 2))] == ["→", "→", "↓", "↓"]
        board.start_episode()
        board.show_scene(lake(agent=(0, 0)))
        await pilot.pause()
        assert centre(board, (0, 1)) == "·" and centre(board, (0, 0)) == "●"


async def test_the_cursor_is_drawn_at_every_size() -> None:
    boards = [(TileBoard(), PLAY_BIG), (TileBoard(), TRAIN_BIG), (TileBoard(), TRAIN_COMPACT)]
    app = BoardApp(boards)
    async with app.run_test(size=(80, screen_height(boards))) as pilot:
        scenes = [
            {"cells": MAZE, "theme": "plain", "agent": (0, 0), "cursor": (2, 1)},
            {"cells": LAKE8, "theme": "lake", "agent": (0, 0), "cursor": (2, 1)},
            {"cells": LAKE4, "theme": "lake", "agent": (0, 0), "cursor": (2, 1)},
        ]
        for (board, _), scene in zip(boards, scenes, strict=True):
            board.show_scene(scene)
        await pilot.pause()
        big, middle, small = (board for board, _ in boards)
        drawn = layout(big)
        x0, y0 = drawn.left + drawn.shape.x_of(1), drawn.top + 2 * drawn.shape.cell_h
        assert char_at(big, Offset(x0, y0)) == "┌"
        assert char_at(big, Offset(x0 + drawn.shape.cell_w - 1, y0 + drawn.shape.cell_h - 1)) == "┘"
        assert "Cursor at row 2, column 1" in text_of(big)
        cursor_colour = big.get_component_rich_style("tile--cursor").bgcolor
        line = tile_line(middle, (2, 1))
        if layout(middle).shape.half:
            assert style_at(middle, layout(middle).cell_center((2, 1))).color == cursor_colour
        else:
            assert line.startswith("[") and line.endswith("]")
        small_spot = layout(small).cell_center((2, 1))
        assert cursor_colour in (
            style_at(small, small_spot).bgcolor,
            style_at(small, small_spot).color,
        )


# --- keys and clicks -----------------------------------------------------------------


async def test_keys_post_moves_by_name_and_new_episodes() -> None:
    board = TileBoard()
    app = BoardApp([(board, PLAY_COMPACT)])
    async with app.run_test(size=(60, 20)) as pilot:
        board.show_scene(lake())
        board.focus()
        await pilot.press("up", "w", "down", "s", "left", "a", "right", "d")
        await pilot.pause()
        names = ["up", "up", "down", "down", "left", "left", "right", "right"]
        assert app.posted == [("act", name) for name in names]
        app.posted.clear()
        await pilot.press("enter")  # mid-episode: a stray Enter loses nothing
        await pilot.press("n", "r")
        board.set_episode_over(True)
        await pilot.press("enter")
        await pilot.pause()
        assert app.posted == [("new",)] * 3
        assert not board.takes_key("p") and board.takes_key("a")
        keys = " ".join(key for key, _ in board.key_help())
        assert "w a s d" in keys and "enter" in keys and "n / r" in keys


async def test_clicks_step_towards_the_cell_and_report_it() -> None:
    board = TileBoard()
    half = TileBoard()
    app = BoardApp([(board, PLAY_BIG), (half, (26, 10))])
    async with app.run_test(size=(80, 36)) as pilot:
        board.show_scene(lake(agent=(2, 1)))
        half.show_scene(lake(LAKE12, agent=(5, 5)))
        await pilot.pause()
        for cell in ((2, 2), (1, 1), (2, 0), (3, 1), (0, 3)):  # the last one far: right first
            await pilot.click(board.canvas, offset=layout(board).cell_center(cell))
        await pilot.pause()
        acts = [item[1] for item in app.posted if item[0] == "act"]
        cells = [item[1:] for item in app.posted if item[0] == "cell"]
        assert acts == ["right", "up", "left", "down", "right"]
        assert cells == [(2, 2), (1, 1), (2, 0), (3, 1), (0, 3)]

        app.posted.clear()
        assert layout(half).shape.half
        await pilot.click(half.canvas, offset=layout(half).cell_center((5, 7)))  # the agent's line
        await pilot.click(half.canvas, offset=layout(half).cell_center((9, 5)))
        await pilot.pause()
        assert app.posted == [("cell", 5, 7), ("act", "right"), ("cell", 8, 5), ("act", "down")]

        app.posted.clear()
        board.set_agent_playing(True)
        await pilot.click(board.canvas, offset=layout(board).cell_center((2, 2)))
        await pilot.pause()
        assert app.posted == [("take over",)]
