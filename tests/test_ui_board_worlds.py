"""`TileBoard` with the book's worlds, mounted alone: the wind drawn, king's moves and a
state's choices by key, moves a state does not offer refused, a game's words in its tone,
and a maze's wall moving in the scene the game hands the board."""

from __future__ import annotations

import gymnasium as gym

from tests.board_support import PLAY_BIG, BoardApp, rows, text_of
from tui_gym.games import game_named
from tui_gym.ui.widgets.tile_board import TileBoard


def _scene(name: str, **kwargs) -> tuple[dict, object]:
    game = game_named(name)
    env = gym.make(game.env_id, **kwargs)
    env.reset(seed=0)
    return game.states.scene(env), env


async def test_the_wind_is_drawn_in_the_tiles_and_under_the_columns() -> None:
    scene, _ = _scene("windy")
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(scene)
        await pilot.pause()
        lines = rows(board)
        strengths = next(line for line in lines if "↑2" in line)
        assert strengths.split() == ["0", "0", "0", "↑1", "↑1", "↑1", "↑2", "↑2", "↑1", "0"]
        assert any("↑↑" in line for line in lines)  # the corner marks of the strongest columns


async def test_kings_moves_and_a_states_choices_go_by_key_and_offered_moves_only() -> None:
    windy, _ = _scene("windy-king")
    walk, _ = _scene("random-walk")
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(windy)
        board.focus()
        await pilot.press("home", "pageup", "end", "pagedown", "7", "3", "8")
        await pilot.pause()
        assert app.posted == [("act", m) for m in (
            "up-left", "up-right", "down-left", "down-right", "up-left", "down-right", "up")]
        app.posted.clear()
        board.show_scene(walk)  # two moves only: the others are not offered
        await pilot.press("up", "home", "7", "right")
        await pilot.pause()
        assert app.posted == [("act", "right")]
        assert "No up here: the moves are left, right" in text_of(board)


async def test_b_offers_its_actions_by_digit_and_a_its_two_moves() -> None:
    scene, env = _scene("max-bias", actions=3)
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        board.show_scene(scene)
        board.focus()
        await pilot.press("1", "left")  # in A: the digits choose nothing
        await pilot.pause()
        assert app.posted == [("act", "left")]
        game = game_named("max-bias")
        before = scene
        env.step(0)
        board.show_scene(game.states.scene(env, before))
        await pilot.pause()
        assert "You went left to B: pick one of its actions (1 to 3)" in text_of(board)
        app.posted.clear()
        await pilot.press("left", "2", "3", "4")
        await pilot.pause()
        assert app.posted == [("act", "b2"), ("act", "b3")]


async def test_the_board_says_when_the_wall_moves() -> None:
    game = game_named("blocking-maze")
    env = gym.make(game.env_id, change_at=2)
    env.reset(seed=0)
    board = TileBoard()
    app = BoardApp([(board, PLAY_BIG)])
    async with app.run_test(size=(80, 30)) as pilot:
        scene = game.states.scene(env)
        for _ in range(2):
            before = scene
            env.step(3)
            scene = game.states.scene(env, before)
        board.show_scene(scene)
        await pilot.pause()
        assert scene["event_tone"] == "slipped"
        assert "The wall moved after 2 steps" in text_of(board)
        assert board.cells[3] == "FWWWWWWWW"
