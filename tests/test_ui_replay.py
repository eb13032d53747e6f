"""Replaying a recording: step forward and back by key and mouse, jump between episodes, the
board showing each recorded scene, the coach's word on each move; recording from the app."""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

import pytest
from textual.app import App
from textual.widgets import OptionList, Static

from tests.waiting import wait_for
from tui_gym.core.recording import Recording, read_recording
from tui_gym.games import GAMES
from tui_gym.session.play import HumanGame
from tui_gym.session.recording.recorder import Recorder
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.jump_screen import JumpScreen
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.replay_screen import ReplayScreen
from tui_gym.ui.widgets.boards import BoardCanvas

SIZE = (120, 40)


class ReplayHost(App[None]):
    """The replay screen alone, over an empty app."""

    def __init__(self, recording: Recording) -> None:
        super().__init__()
        self.recording = recording

    def on_mount(self) -> None:
        self.push_screen(ReplayScreen(self.recording))


def record(path: Path, env: str, episodes: int, seed: int = 0, moves: int = 40) -> Path:
    """`episodes` episodes of random moves (at most `moves` each) recorded to `path`."""
    session = Session(env, seed=seed)
    game = HumanGame(session, seed=seed)
    rng = random.Random(seed)
    names = list(session.game.action_names)
    with Recorder(path, session, source="app", seed=seed) as recorder:
        game.recorder = recorder
        for _ in range(episodes):
            game.reset()
            while not game.done and game.last is not None and game.last.steps < moves:
                game.step(rng.choice(names))
    return path


def said(screen: ReplayScreen, selector: str) -> str:
    return str(screen.query_one(selector, Static).render())


def drawing(screen: ReplayScreen) -> str:
    assert screen.board is not None
    return str(screen.board.canvas.render())


async def test_step_jump_and_see_the_coach_judge_each_move(tmp_path: Path) -> None:
    recording = read_recording(record(tmp_path / "bj.jsonl", "blackjack", 5, seed=2))
    host = ReplayHost(recording)
    async with host.run_test(size=SIZE) as pilot:
        await pilot.pause()
        screen = host.screen
        assert isinstance(screen, ReplayScreen)
        assert said(screen, "#replay-headline") == "Start of hand 1 (seed 2)"
        assert "hand 1 of 5" in said(screen, "#replay-title")
        first = recording.episodes[0]
        start_picture = drawing(screen)
        assert screen.board is not None and screen.board.scene == first.positions[0].frame.scene

        await pilot.press("right")
        move = first.positions[1].move
        assert move is not None
        assert (screen.episode_index, screen.position) == (0, 1)
        assert screen.board.scene == first.positions[1].frame.scene
        assert drawing(screen) != start_picture
        headline = said(screen, "#replay-headline")
        assert headline.startswith(f"Move 1 of {len(first.moves)}: {move.action_name}")
        coach = said(screen, "#replay-coach")
        mark = "✓" if move.verdict == "optimal" else "✗"
        assert coach.startswith(f"{mark} {move.action_name} was ")
        assert f"regret {move.regret:.3f}" in coach
        assert f"regret so far {first.running_regret(1):.3f}" in coach

        await pilot.press("left")
        assert screen.position == 0 and drawing(screen) == start_picture
        await pilot.press("n")
        assert (screen.episode_index, screen.position) == (1, 0)
        assert said(screen, "#replay-headline").startswith("Start of hand 2")
        await pilot.press("N")
        assert screen.episode_index == 0

        await pilot.press("j")
        assert isinstance(host.screen, JumpScreen)
        await pilot.press("9", "enter")  # the field starts selected; out of range: said
        jump = host.screen
        assert isinstance(jump, JumpScreen) and "1 to 5" in jump.error
        await pilot.press("backspace", "4", "enter")
        assert host.screen is screen and screen.episode_index == 3

        await pilot.press("end")
        last = recording.episodes[3]
        assert screen.position == len(last.positions) - 1
        assert "Move" in said(screen, "#replay-headline")

        # The mouse: buttons and the list of moves.
        await pilot.click("#replay-next-episode")
        assert (screen.episode_index, screen.position) == (4, 0)
        await pilot.click("#replay-forward")
        assert screen.position == 1
        await pilot.click("#replay-back")
        assert screen.position == 0
        moves = screen.query_one("#replay-moves", OptionList)
        assert moves.option_count == len(recording.episodes[4].positions)
        moves.highlighted = 1  # what a click on the first move does
        await pilot.pause()
        assert screen.position == 1
        await pilot.press("escape")
        assert not isinstance(host.screen, ReplayScreen)


async def test_a_broken_file_replays_its_good_lines_with_one_message(tmp_path: Path) -> None:
    path = record(tmp_path / "broken.jsonl", "blackjack", 3)
    lines = path.read_text().splitlines()
    lines.insert(3, "{broken")
    lines.append('{"type": "step", "episode"')  # cut short by a crash
    path.write_text("\n".join(lines) + "\n")
    recording = read_recording(path)
    host = ReplayHost(recording)
    async with host.run_test(size=SIZE) as pilot:
        await pilot.pause()
        notes = list(host._notifications)
        assert len(notes) == 1
        assert notes[0].severity == "warning"
        assert "2 lines could not be read" in notes[0].message
        assert f"(lines 4, {len(lines)})" in notes[0].message
        screen = host.screen
        assert isinstance(screen, ReplayScreen)
        await pilot.press("n", "n")
        assert screen.episode_index == 2


# One game of each board kind: the replay screen steps every game's scenes alike, and what
# differs between games is the board that draws them.
BOARD_KINDS = [game for game in GAMES if game is next(g for g in GAMES if g.board == game.board)]


@pytest.mark.parametrize("profile", BOARD_KINDS, ids=lambda p: p.name)
async def test_every_board_kind_replays_forward_and_back_alike(
    tmp_path: Path, profile: Any
) -> None:
    recording = read_recording(record(tmp_path / "game.jsonl", profile.env_id, 1, seed=4, moves=8))
    episode = recording.episodes[0]
    host = ReplayHost(recording)
    async with host.run_test(size=(80, 24)) as pilot:
        screen = host.screen
        assert isinstance(screen, ReplayScreen) and screen.board is not None
        board = screen.board
        await pilot.press("end", "home")  # the screen has laid itself out
        size = board.query_one(BoardCanvas).content_size

        def draw() -> str:
            # Drawn twice: a board keeps the cell shape of its last drawing, and the
            # screen's own drawings come in between the test's.
            board.picture(size.width, size.height)
            return str(board.picture(size.width, size.height))

        forward = []
        for _ in episode.positions:  # the keys are pressed in the test above: here, their actions
            forward.append(draw())
            screen.action_step(1)
        assert len(set(forward)) > 1  # the scene changes as the moves go by
        await pilot.press("end")
        backward = []
        for _ in episode.positions:
            backward.append(draw())
            screen.action_step(-1)
        assert backward[::-1] == forward


async def test_a_board_this_version_lacks_shows_the_state_in_words(tmp_path: Path) -> None:
    path = record(tmp_path / "bj.jsonl", "blackjack", 1)
    records = [json.loads(line) for line in path.read_text().splitlines()]
    records[0]["board"] = "hexagons"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    host = ReplayHost(read_recording(path))
    async with host.run_test(size=SIZE):
        screen = host.screen
        assert isinstance(screen, ReplayScreen) and screen.board is None
        first = records[1]
        assert str(screen.query_one("#replay-words", Static).render()) == first["text"]


async def test_the_app_records_while_switched_on_and_replays_it(tmp_path: Path) -> None:
    path = tmp_path / "mine.jsonl"
    app = TuiGymApp(Session("blackjack", seed=1), record=path)
    async with app.run_test(size=SIZE) as pilot:
        view = app.query_one(PlayView)
        title = view.query_one("#play-title", Static)
        await wait_for(pilot, lambda: "● REC mine.jsonl" in str(title.render()),
                       "recording switched on after the first frame")
        await pilot.press("s")  # stick: the hand ends
        await pilot.press("n", "h")
        await pilot.press("ctrl+r")
        assert "REC" not in str(view.query_one("#play-title", Static).render())
        titles = [command.title for command in app.get_system_commands(app.screen)]
        assert "Record games" in titles
    recording = read_recording(path)
    assert [len(e.moves) for e in recording.episodes] == [1, 1]
    assert recording.episodes[0].game.source == "app"
    assert recording.episodes[0].finished
    replay = TuiGymApp(Session("blackjack", seed=1), replay=recording)
    async with replay.run_test(size=SIZE) as pilot:
        await pilot.pause()
        assert isinstance(replay.screen, ReplayScreen)
        await pilot.press("right")
        assert replay.screen.position == 1
        await pilot.press("escape")
        assert replay.screen is replay.query_one(PlayView).screen  # back in the app
