"""Recordings: what the recorder writes, the coach's verdict and exact regret, the writer's
whole lines, and a reader that replays what it can of a damaged or foreign file."""

from __future__ import annotations

import io
import json
import random
import sys
from pathlib import Path
from typing import Any

import pytest

from tui_gym.cli import main
from tui_gym.core.mdp import model_from_env, solve
from tui_gym.core.recording import (
    FORMAT_VERSION,
    MoveJudge,
    RecordingError,
    read_recording,
)
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games import GAMES
from tui_gym.session.play import HumanGame
from tui_gym.session.recording.recorder import Recorder
from tui_gym.session.recording.scenes import scene_fits
from tui_gym.session.recording.switch import RecordingSwitch
from tui_gym.session.session import Session


def lines_of(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def play(game: HumanGame, actions: list[str], episodes: int = 1) -> None:
    """Play `episodes` episodes, cycling through `actions` (a game ends whatever is asked)."""
    rng = random.Random(0)
    for _ in range(episodes):
        game.reset()
        while not game.done and game.last is not None and game.last.steps < 60:
            game.step(rng.choice(actions))


# --- what is written -------------------------------------------------------------------
def test_a_blackjack_recording_holds_each_move_and_its_exact_regret(tmp_path: Path) -> None:
    session = Session("blackjack", seed=3)
    game = HumanGame(session, seed=3)
    path = tmp_path / "bj.jsonl"
    with Recorder(path, session, source="play", seed=3) as recorder:
        game.recorder = recorder
        for _ in range(6):
            game.reset()
            before = session.game.oracle.advice(game.env, session.env_kwargs)
            game.step("hit")
            expected = max(before.values.values()) - before.values[1]
            step = [r for r in lines_of(path) if r["type"] == "step"][-1]
            assert step["type"] == "step" and step["action_name"] == "hit"
            assert step["regret"] == pytest.approx(expected, abs=1e-12)
            assert step["verdict"] == ("optimal" if 1 in before.optimal else "not optimal")
    records = lines_of(path)
    header = records[0]
    assert header["type"] == "header" and header["version"] == FORMAT_VERSION
    assert (header["game"], header["env_id"], header["seed"]) == ("blackjack", "Blackjack-v1", 3)
    assert header["actions"] == ["stick", "hit"] and header["board"] == "cards"
    starts = [r for r in records if r["type"] == "start"]
    assert [r["episode"] for r in starts] == list(range(1, 7))
    assert starts[0]["seed"] == 3  # the first reset uses the game's seed
    assert {"player", "dealer"} <= set(starts[0]["scene"])
    ends = [r for r in records if r["type"] == "end"]
    assert len(ends) == 6  # finished hands end; the last unfinished one ends on close
    recording = read_recording(path)
    assert recording.message is None
    assert [e.total_return for e in recording.episodes] == [e["return"] for e in ends]
    for episode, end in zip(recording.episodes, ends, strict=True):
        total = episode.running_regret(len(episode.positions) - 1)
        assert total == pytest.approx(end["regret"])


@pytest.mark.parametrize("profile", GAMES, ids=lambda p: p.name)
def test_every_game_records_and_reads_back(tmp_path: Path, profile: Any) -> None:
    session = Session(profile.env_id, seed=5)
    game = HumanGame(session, seed=5)
    path = tmp_path / f"{profile.name}.jsonl"
    with Recorder(path, session, source="benchmark", seed=5) as recorder:
        game.recorder = recorder
        play(game, list(profile.action_names), episodes=3)
    recording = read_recording(path, scene_fits)  # every scene fits the game's own board
    assert recording.message is None and recording.unfit_scenes == 0
    assert [e.index for e in recording.episodes] == [1, 2, 3]
    for episode in recording.episodes:
        assert episode.game.board == profile.board
        assert episode.positions[0].move is None
        moves = episode.moves
        assert [m.step for m in moves] == list(range(1, len(moves) + 1))
        assert all(isinstance(p.frame.scene, dict) for p in episode.positions)
        assert episode.total_return == pytest.approx(sum(m.reward for m in moves))
        assert all(m.verdict in ("optimal", "not optimal", None) for m in moves)


def test_a_new_header_follows_a_change_of_game_and_the_switch_adds_to_its_file(
    tmp_path: Path,
) -> None:
    path = tmp_path / "games.jsonl"
    switch = RecordingSwitch(path)
    blackjack = HumanGame(Session("blackjack", seed=1), seed=1)
    blackjack.recorder = switch
    blackjack.reset()
    assert switch.turn_on(blackjack) == path  # no move yet: this hand is recorded whole
    blackjack.step("stick")
    grid = HumanGame(Session("gridworld", seed=2), seed=2)
    grid.recorder = switch
    grid.reset()
    grid.step("up")
    blackjack.reset()  # back to the first game: a header again
    assert switch.turn_off() == path
    blackjack.step("stick")  # switched off: not recorded
    blackjack.reset()
    switch.turn_on(blackjack)
    switch.turn_off()
    kinds = [(r["type"], r.get("game")) for r in lines_of(path)]
    assert [k for k in kinds if k[0] == "header"] == [
        ("header", "blackjack"), ("header", "gridworld"), ("header", "blackjack"),
        ("header", "blackjack"),
    ]
    recording = read_recording(path)
    assert [e.game.game for e in recording.episodes] == [
        "blackjack", "gridworld", "blackjack", "blackjack"
    ]
    assert [len(e.moves) for e in recording.episodes] == [1, 1, 0, 0]
    assert not recording.episodes[2].finished  # abandoned when the switch went off


# --- the coach's judgement ----------------------------------------------------------------
def test_gridworld_moves_get_a_verdict_but_no_regret(tmp_path: Path) -> None:
    session = Session("gridworld", seed=0)
    game = HumanGame(session, seed=0)
    path = tmp_path / "grid.jsonl"
    with Recorder(path, session) as recorder:
        game.recorder = recorder
        game.reset()
        optimal = session.game.oracle.advice(game.env, session.env_kwargs).optimal
        wrong = next(a for a in range(4) if a not in optimal)
        game.step(wrong)
    step = next(r for r in lines_of(path) if r["type"] == "step")
    assert step["verdict"] == "not optimal" and step["regret"] is None
    assert step["optimal"] == [session.game.action_names[a] for a in optimal]
    end = lines_of(path)[-1]
    assert end["type"] == "end" and end["regret"] is None


def test_a_wrapper_beyond_the_exact_figures_leaves_moves_unjudged(tmp_path: Path) -> None:
    session = Session("blackjack", seed=0,
                      choices=(WrapperChoice.make("StickyAction", repeat_action_probability=0.25),))
    game = HumanGame(session, seed=0)
    path = tmp_path / "sticky.jsonl"
    with Recorder(path, session) as recorder:
        game.recorder = recorder
        game.reset()
        game.step("stick")
    step = next(r for r in lines_of(path) if r["type"] == "step")
    assert (step["verdict"], step["regret"], step["optimal"]) == (None, None, [])
    (wrapper,) = lines_of(path)[0]["wrappers"]
    assert wrapper.startswith("StickyAction:repeat_action_probability=0.25")


def test_games_with_a_model_get_the_exact_regret_for_the_steps_left() -> None:
    session = Session("frozenlake", {"slippery": True}, seed=1,
                      choices=(WrapperChoice.make("TimeLimit", max_episode_steps=20),))
    env = session.env
    judge = MoveJudge(session.game, session.env_kwargs)
    model = model_from_env(env)
    assert model.horizon == 20
    env.reset(seed=1)
    for steps_taken in range(3):
        state = int(env.unwrapped.s)
        q = solve(model, steps_left=20 - steps_taken).q[state]
        assessment = judge.assess(env)
        for action in range(4):
            judgement = assessment.judge(action)
            assert judgement.regret == pytest.approx(q.max() - q[action], abs=1e-12)
            if judgement.verdict == "optimal":
                assert q[action] >= q.max() - 1e-9
            if q[action] < q.max() - 1e-9:
                assert judgement.verdict == "not optimal"
        _, _, terminated, truncated, _ = env.step(int(q.argmax()))
        if terminated or truncated:
            break


# --- the writer -----------------------------------------------------------------------------
def test_a_failed_write_leaves_whole_lines_and_stops_only_the_recording(tmp_path: Path) -> None:
    session = Session("blackjack", seed=0)
    game = HumanGame(session, seed=0)
    path = tmp_path / "full.jsonl"
    told: list[str] = []
    recorder = Recorder(path, session, on_failure=told.append)
    game.recorder = recorder
    game.reset()
    writer = recorder._writer
    assert writer is not None

    def half_then_full(fd: int, data: bytes) -> int:  # the disk fills up mid-line
        if len(data) > 10:
            import os

            return os.write(fd, data[: len(data) // 2])
        raise OSError(28, "No space left on device")

    writer._raw_write = half_then_full  # type: ignore[method-assign]
    game.step("hit")  # the game goes on
    assert told == [f"recording to {path} stopped: No space left on device"]
    assert recorder.failure == told[0] and not recorder.active
    text = path.read_text()
    assert text.endswith("\n")
    assert [json.loads(line)["type"] for line in text.splitlines()] == ["header", "start"]
    game.reset()  # nothing more is written, nothing raises
    recorder.close()
    assert path.read_text() == text


# --- the reader ------------------------------------------------------------------------------
def _good_file(tmp_path: Path) -> Path:
    session = Session("blackjack", seed=4)
    game = HumanGame(session, seed=4)
    path = tmp_path / "good.jsonl"
    with Recorder(path, session) as recorder:
        game.recorder = recorder
        play(game, ["hit", "stick"], episodes=4)
    return path


def test_a_damaged_file_from_another_version_replays_the_rest_with_one_message(
    tmp_path: Path,
) -> None:
    lines = _good_file(tmp_path).read_text().splitlines()
    header = json.loads(lines[0])
    header["version"] = FORMAT_VERSION + 1
    lines[0] = json.dumps(header)
    first_end = next(i for i, line in enumerate(lines) if '"type": "end"' in line)
    lines.insert(first_end + 1, "{not json")
    lines.insert(first_end + 2, json.dumps({"type": "teleport", "episode": 9}))
    lines.insert(first_end + 3, '{"type": "step", "episode": 2, "step": "one"}')
    lines[-1] = lines[-1][: len(lines[-1]) // 2]  # a line cut short by a crash
    path = tmp_path / "damaged.jsonl"
    path.write_bytes(("\n".join(lines)).encode() + b"\n\xff\xfe\n")
    recording = read_recording(path)
    bad = [first_end + 2, first_end + 3, first_end + 4, len(lines), len(lines) + 1]
    assert recording.skipped == bad
    message = recording.message
    assert message == (
        f"damaged.jsonl: it was written in recording format version {FORMAT_VERSION + 1} and "
        f"this tui-gym reads version {FORMAT_VERSION}; 5 lines could not be read and were "
        f"skipped (lines {', '.join(map(str, bad))}); the rest replays."
    )
    assert len(recording.episodes) == 4
    assert recording.episodes[-1].end is None  # its end line was the one cut short


def test_an_episode_whose_start_was_lost_begins_at_its_first_move(tmp_path: Path) -> None:
    lines = _good_file(tmp_path).read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if '"type": "start"' in line)
    lines[start] = "garbage"
    path = tmp_path / "lost.jsonl"
    path.write_text("\n".join(lines) + "\n")
    recording = read_recording(path)
    first = recording.episodes[0]
    assert not first.started and first.positions[0].move is not None
    assert recording.skipped == [start + 1]
    assert "1 line could not be read and was skipped (line 2)" in (recording.message or "")


def test_files_with_nothing_to_replay_are_refused_with_one_line(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match="missing.jsonl: no such file"):
        read_recording(tmp_path / "missing.jsonl")
    with pytest.raises(RecordingError, match="is a folder"):
        read_recording(tmp_path)
    junk = tmp_path / "junk.txt"
    junk.write_text("hello\nworld\n")
    with pytest.raises(RecordingError, match="is not a tui-gym recording"):
        read_recording(junk)
    empty = tmp_path / "empty.jsonl"
    Recorder(empty, Session("blackjack")).close()
    with pytest.raises(RecordingError, match="holds no episode"):
        read_recording(empty)


# --- the command line -----------------------------------------------------------------------
def test_play_jsonl_records_what_the_program_played(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    requests = b'{"cmd":"reset","seed":7}\n{"cmd":"step","action":"hit"}\n{"cmd":"step"}\n'
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(requests)))
    path = tmp_path / "program.jsonl"
    assert main(["play", "blackjack", "--jsonl", "--record", str(path)]) == 0
    answers = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert "error" in answers[-1]  # a bad request is not a move
    records = lines_of(path)
    assert [r["type"] for r in records] == ["header", "start", "step", "end"]
    assert records[0]["source"] == "play"
    assert records[1]["observation"] == answers[0]["observation"]
    assert records[2]["observation"] == answers[1]["observation"]
    assert records[2]["reward"] == answers[1]["reward"]


def test_record_paths_that_cannot_be_written_are_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b"")))
    missing = tmp_path / "no" / "such.jsonl"
    for argv, said in (
        (["play", "blackjack", "--jsonl", "--record", str(tmp_path)],
         f"tui-gym play: error: argument --record: {tmp_path}: is a folder; give a file name\n"),
        (["play", "blackjack", "--jsonl", "--record", str(missing)],
         f"tui-gym play: error: argument --record: {missing}: the folder {missing.parent} does "
         "not exist\n"),
        (["--record", str(missing)],
         f"tui-gym: error: argument --record: {missing}: the folder {missing.parent} does not "
         "exist\n"),
    ):
        with pytest.raises(SystemExit) as exit_:
            main(argv)
        assert exit_.value.code == 2 and capsys.readouterr().err == said
    assert main(["replay", str(tmp_path / "none.jsonl")]) == 2
    assert "none.jsonl: no such file\n" in capsys.readouterr().err
