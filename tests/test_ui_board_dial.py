"""`DialBoard` mounted alone: the dial stops at the moves a state allows, Enter makes the
move it points at, and it tells which keys pick a move; the tile board says a jump in the
game's own words."""

from __future__ import annotations

from tests.board_support import PLAY_BIG, PLAY_COMPACT, BoardApp, rows
from tui_gym.ui.widgets.dial_board import DialBoard
from tui_gym.ui.widgets.tile_board import TileBoard

STAKES = [f"stake {k}" for k in range(1, 51)]


def stake_scene(capital: int, **extra) -> dict:
    return {"title": "Gambler", "bars": [["capital", capital, 100]], "actions": STAKES,
            "labels": [f"${k}" for k in range(1, 51)], "allowed": min(capital, 100 - capital),
            "unit": "$", "lines": ["{who} staked $2: heads, won"], **extra}


async def test_the_dial_turns_within_the_allowed_moves_and_makes_one() -> None:
    board, small = DialBoard(), DialBoard()
    app = BoardApp([(board, PLAY_BIG), (small, PLAY_COMPACT)])
    async with app.run_test(size=(PLAY_BIG[0], PLAY_BIG[1] + PLAY_COMPACT[1])) as pilot:
        board.show_scene(stake_scene(3))
        small.show_scene(stake_scene(60))
        board.focus()
        await pilot.press("right", "right", "right", "right")
        assert board.pointer == 2  # a capital of 3 stakes at most 3
        await pilot.press("enter")
        assert app.posted[-1] == ("act", "stake 3")
        assert board.keys_for("stake 1") == ["left", "left", "enter"]
        text = "\n".join(rows(board))
        assert "You staked $2: heads, won" in text and "$3/$100" in text and "$3" in text
        small.focus()
        await pilot.press("up", "up", "end")
        assert small.pointer == 39  # 60 stakes up to the 40 missing to the goal
        await pilot.press("home", "n")
        assert small.pointer == 0 and app.posted[-1] == ("new",)
        board.show_scene(stake_scene(90))  # fewer moves now: the pointer comes back within
        assert board.pointer == 2
        board.set_episode_over(True)
        board.focus()
        await pilot.press("enter")  # once over, Enter starts the next episode
        assert app.posted[-1] == ("new",)


async def test_a_new_episode_points_the_dial_at_its_start() -> None:
    board = DialBoard()
    app = BoardApp([(board, PLAY_BIG)])
    moves = ["-1", "0", "+1"]
    async with app.run_test(size=PLAY_BIG) as pilot:
        board.show_scene({"actions": moves, "start": 1})
        assert board.pointer == 1
        board.focus()
        await pilot.press("left")
        board.show_scene({"actions": moves, "start": 1})  # the same episode: kept
        assert board.pointer == 0
        board.start_episode()
        board.show_scene({"actions": moves, "start": 1})
        assert board.pointer == 1


async def test_the_tile_board_says_a_jump_in_the_games_words() -> None:
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=PLAY_BIG):
        cells = ["FAFBF"] + ["FFFFF"] * 4
        board.show_scene({"cells": cells, "theme": "plain", "agent": (0, 1)})
        board.show_scene({"cells": cells, "theme": "plain", "agent": (4, 1), "last_action": "up",
                          "event": "{who} jumped from A to A′: +10"})
        assert board.event_text == "You jumped from A to A′: +10"
