"""Recordings are data: scenes their board cannot draw are dropped (a hand of 100,000 cards,
a grid 100,000 cells a side), a long file is read up to a cap with a line saying so, and
text from the file never reaches the terminal with its control characters. A seeded
generator of damaged recordings checks that every one reads soundly or is refused in one
line, and a few replay in the app's replay screen."""

from __future__ import annotations

import functools
import json
import random
import tempfile
from pathlib import Path
from typing import Any

import pytest

from tests.test_ui_replay import SIZE, ReplayHost, record
from tui_gym.core.recording import RecordingError, read_recording
from tui_gym.core.recording import reader as recording_reader
from tui_gym.games import GAMES
from tui_gym.session.recording.scenes import scene_fits
from tui_gym.ui.replay_screen import ReplayScreen

CONTROL = "\x1b]2;PWNED\x07\x1b[2J\x1b]52;c;ZXZpbA==\x07\u202e"
CASES = 150


def _write(path: Path, records: list[Any]) -> Path:
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    return path


def _lines(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def _no_control(text: str) -> bool:
    return all(c == "\n" or (c.isprintable() and c != "\u202e") for c in text)


@functools.cache
def _short_recording(game: str) -> str:
    """A recorded episode of `game` of at most three moves (recorded once per game)."""
    with tempfile.TemporaryDirectory() as folder:
        return record(Path(folder) / "short.jsonl", game, 1, seed=3, moves=3).read_text()


def _with_scene(path: Path, game: str, scene: dict[str, Any]) -> Path:
    records = [json.loads(line) for line in _short_recording(game).splitlines()]
    for line in records[1:]:
        if line["type"] in ("start", "step"):
            line["scene"] = {**line["scene"], **scene}
    return _write(path, records)


@pytest.mark.parametrize(("game", "scene"), [
    ("blackjack", {"player": [10] * 100_000}),
    ("blackjack", {"dealer": ["K"]}),
    ("gridworld", {"size": 100_000}),
    ("gridworld", {"agent": [0, 99]}),
    ("frozenlake", {"rows": 100_000}),
    ("frozenlake", {"cells": ["S" * 5000] * 4}),
    ("taxi", {"rows": 10**9}),
    ("taxi", {"walls": [[0, 0]] * 100_000}),
])
async def test_a_scene_its_board_cannot_draw_is_dropped(
    game: str, scene: dict[str, Any], tmp_path: Path
) -> None:
    path = _with_scene(tmp_path / "bad.jsonl", game, scene)
    recording = read_recording(path, scene_fits)
    frames = [p.frame for e in recording.episodes for p in e.positions]
    assert frames and all(f.scene is None for f in frames)
    assert f"{len(frames)} scenes did not fit their game and are not drawn" in str(
        recording.message)
    if scene in ({"player": [10] * 100_000}, {"size": 100_000}):  # the two that hurt the app
        host = ReplayHost(recording)
        async with host.run_test(size=SIZE) as pilot:  # the moves draw without the scenes
            await pilot.pause()
            assert isinstance(host.screen, ReplayScreen)
            await pilot.press("right", "right", "end")
            await pilot.pause()
            assert "no picture recorded here" in str(host.screen.query_one("#replay-detail")
                                                      .render())


def test_a_long_recording_is_read_up_to_the_cap_with_a_line_saying_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = record(tmp_path / "long.jsonl", "blackjack", 40, seed=5)
    whole = read_recording(path)
    monkeypatch.setattr(recording_reader, "MAX_READ_BYTES", path.stat().st_size // 4)
    cut = read_recording(path)
    assert 1 <= len(cut.episodes) < len(whole.episodes) // 3
    assert cut.cut_at_line is not None and cut.lines == cut.cut_at_line - 1
    message = str(cut.message)
    assert message.endswith(f"and only its first 0 MB (up to line {cut.lines:,}) are read; "
                            "what was read replays.")


async def test_text_from_the_file_shows_its_control_characters(tmp_path: Path) -> None:
    records = _lines(record(tmp_path / "r.jsonl", "blackjack", 1, seed=2, moves=2))
    for line in records:
        if line["type"] == "header":
            line.update(title=CONTROL, source=CONTROL, actions=[CONTROL, CONTROL],
                        episode_noun=CONTROL, wrappers=[CONTROL])
        elif line["type"] in ("start", "step"):
            line.update(text=f"{CONTROL}\nsecond line", observation=CONTROL)
            if line["type"] == "step":
                line.update(action_name=CONTROL, note=CONTROL * 100, optimal=[CONTROL])
    recording = read_recording(_write(tmp_path / "r.jsonl", records), scene_fits)
    game = recording.episodes[0].game
    shown = [game.title, game.source, game.episode_noun, *game.actions, *game.wrappers]
    for position in recording.episodes[0].positions:
        shown.append(position.frame.text or "")
        if position.move is not None:
            shown += [position.move.action_name, position.move.note, *position.move.optimal]
    assert all(_no_control(text) for text in shown), shown
    assert "\\x1b]2;PWNED" in game.title and "\nsecond line" in shown[-4]
    assert max(map(len, shown)) < 400
    host = ReplayHost(recording)
    async with host.run_test(size=SIZE) as pilot:
        await pilot.pause()
        for _ in range(3):
            await pilot.press("right")
            await pilot.pause()
            for widget in host.screen.query("Static"):
                assert "\x1b" not in str(widget.render())


# --- a seeded generator of damaged recordings -----------------------------------------------

HOSTILE_VALUES: list[Any] = [
    None, True, -1, 0, 10**400, 1e308, "", CONTROL, "x" * 5000, [], {}, [[[[[]]]]],
    list(range(2000)), {"k": CONTROL}, "nan", -0.0,
]


def _hostile(rng: random.Random) -> Any:
    return rng.choice(HOSTILE_VALUES)


def damaged(rng: random.Random, good: list[dict[str, Any]]) -> list[Any]:
    """`good` with a few lines changed: fields set to hostile values, scene fields blown
    up, lines dropped, duplicated or replaced by other JSON."""
    records = json.loads(json.dumps(good))
    for _ in range(rng.randint(1, 6)):
        line = rng.choice(records)
        kind = rng.randrange(6)
        if kind == 0 and isinstance(line, dict):
            line[rng.choice(list(line) or ["type"])] = _hostile(rng)
        elif kind == 1 and isinstance(line, dict) and isinstance(line.get("scene"), dict):
            scene = line["scene"]
            if scene:
                scene[rng.choice(list(scene))] = _hostile(rng)
        elif kind == 2:
            records.remove(line)
        elif kind == 3:
            records.insert(rng.randrange(len(records) + 1), line)
        elif kind == 4:
            records[records.index(line)] = _hostile(rng)
        elif isinstance(line, dict):
            line[rng.choice(["text", "action_name", "note", "title", "board"])] = _hostile(rng)
    return records


@pytest.fixture(scope="module")
def good_recordings(tmp_path_factory: pytest.TempPathFactory) -> list[list[dict[str, Any]]]:
    folder = tmp_path_factory.mktemp("good")
    return [_lines(record(folder / f"{g.name}.jsonl", g.name, 2, seed=4, moves=6))
            for g in GAMES]


def test_every_damaged_recording_reads_soundly_or_is_refused_in_one_line(
    good_recordings: list[list[dict[str, Any]]], tmp_path: Path
) -> None:
    rng = random.Random(2024)
    read = refused = 0
    for case in range(CASES):
        records = damaged(rng, rng.choice(good_recordings))
        path = _write(tmp_path / f"case{case}.jsonl", records)
        try:
            recording = read_recording(path, scene_fits)
        except RecordingError as error:
            assert "\n" not in str(error)
            refused += 1
            continue
        read += 1
        assert recording.message is None or "\n" not in recording.message
        for episode in recording.episodes:
            assert _no_control(episode.game.title) and _no_control(episode.game.source)
            for position in episode.positions:
                scene = position.frame.scene
                assert scene is None or scene_fits(episode.game.board, scene)
                assert _no_control(position.frame.text or "")
                if position.move is not None:
                    assert _no_control(position.move.action_name + position.move.note)
    assert read > CASES // 2 and refused < CASES // 2


async def test_damaged_recordings_replay_in_the_app(
    good_recordings: list[list[dict[str, Any]]], tmp_path: Path
) -> None:
    rng = random.Random(7)
    recordings = []
    for case in range(3):
        path = _write(tmp_path / f"case{case}.jsonl", damaged(rng, good_recordings[case % 5]))
        try:
            recordings.append(read_recording(path, scene_fits))
        except RecordingError:
            continue
    assert len(recordings) >= 2
    host = ReplayHost(recordings[0])
    async with host.run_test(size=SIZE) as pilot:
        for recording in recordings:
            if getattr(host.screen, "recording", None) is not recording:
                await host.push_screen(ReplayScreen(recording))
            await pilot.pause()
            for key in ("right", "right", "end", "n", "left", "N"):
                await pilot.press(key)
            await pilot.pause()
            assert isinstance(host.screen, ReplayScreen)
            host.pop_screen()
