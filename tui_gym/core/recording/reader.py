"""`read_recording`: a recording file read back, tolerantly, for replay."""

from __future__ import annotations

import json
import math
import os
import stat
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from tui_gym.core.recording.format import (
    END,
    FORMAT_NAME,
    FORMAT_VERSION,
    HEADER,
    OPTIMAL,
    START,
    STEP,
    VERDICTS,
)
from tui_gym.core.text import visible

MAX_LINE_BYTES = 1 << 20  # longer lines are skipped unread
MAX_READ_BYTES = 32 << 20  # a file's first bytes that are read; the rest is left
MAX_WRAPPERS = 32  # a header's wrappers, at most (a chain's length)
LINES_NAMED = 10  # bad lines named in the message; the rest are counted
NAME_CHARS = 80  # names, titles and labels from the file
TEXT_CHARS = 200  # each line of a note or of the state in words
TEXT_LINES = 40  # lines of the state in words

SceneCheck = Callable[[str, Mapping[str, Any]], bool]


class RecordingError(ValueError):
    """A file that cannot be replayed at all (not there, or no episode in it)."""


@dataclass(frozen=True)
class RecordedGame:
    """A header: which game the episodes after it were played in."""

    line: int
    version: int | None
    tui_gym: str
    source: str
    game: str
    title: str
    env_id: str
    env_kwargs: Mapping[str, Any]
    wrappers: tuple[str, ...]
    seed: int | None
    board: str
    actions: tuple[str, ...]
    episode_noun: str

    def action_name(self, action: int) -> str:
        return self.actions[action] if 0 <= action < len(self.actions) else str(action)


UNKNOWN_GAME = RecordedGame(0, None, "", "", "", "unknown game", "", {}, (), None, "", (),
                            "episode")


@dataclass(frozen=True)
class Frame:
    """A state as recorded: the observation, the board's scene, the state in words."""

    observation: Any
    scene: Mapping[str, Any] | None
    text: str | None
    info: Mapping[str, Any]


@dataclass(frozen=True)
class Move:
    """One recorded move and the coach's judgement of it."""

    step: int
    action: int
    action_name: str
    reward: float
    terminated: bool
    truncated: bool
    verdict: str | None
    regret: float | None
    optimal: tuple[str, ...]
    note: str = ""

    @property
    def done(self) -> bool:
        return self.terminated or self.truncated


@dataclass(frozen=True)
class Position:
    """One place to stand in an episode: a state, and the move that led to it (None first)."""

    frame: Frame
    move: Move | None


@dataclass(frozen=True)
class EpisodeEnd:
    """An episode's end line."""

    steps: int
    episode_return: float
    terminated: bool
    truncated: bool
    regret: float | None


@dataclass
class Episode:
    """One recorded episode: its positions in order, from the reset (when recorded) on."""

    index: int  # 1, 2, ... in the order of the file
    game: RecordedGame
    seed: int | None = None
    started: bool = True  # False when its start line was lost (it begins at its first move)
    positions: list[Position] = field(default_factory=list)
    end: EpisodeEnd | None = None
    recorded_number: int = 0  # the number the file gave it

    @property
    def moves(self) -> list[Move]:
        return [p.move for p in self.positions if p.move is not None]

    @property
    def total_return(self) -> float:
        if self.end is not None:
            return self.end.episode_return
        return sum(move.reward for move in self.moves)

    @property
    def finished(self) -> bool:
        """Whether it ended by terminating or being truncated (not abandoned or cut off)."""
        if self.end is not None:
            return self.end.terminated or self.end.truncated
        moves = self.moves
        return bool(moves) and moves[-1].done

    def running_regret(self, position: int) -> float | None:
        """The sum of the regrets of the moves up to `position` (None when one is unknown)."""
        total = 0.0
        for place in self.positions[: position + 1]:
            move = place.move
            if move is None or move.verdict is None:
                continue  # no decision to judge: costs nothing
            if move.regret is None:
                return None
            total += move.regret
        return total

    def running_return(self, position: int) -> float:
        return sum(p.move.reward for p in self.positions[: position + 1] if p.move is not None)

    @property
    def judged(self) -> tuple[int, int]:
        """(moves judged optimal, moves judged) over the episode."""
        verdicts = [m.verdict for m in self.moves if m.verdict is not None]
        return sum(v == OPTIMAL for v in verdicts), len(verdicts)


@dataclass
class Recording:
    """A recording file as read: its games and episodes, and what could not be read."""

    path: Path
    games: list[RecordedGame] = field(default_factory=list)
    episodes: list[Episode] = field(default_factory=list)
    skipped: list[int] = field(default_factory=list)  # numbers of the lines not read
    versions: set[int | None] = field(default_factory=set)  # versions of headers not ours
    missing_header: bool = False
    lines: int = 0
    unfit_scenes: int = 0  # scenes their board cannot draw, dropped
    cut_at_line: int | None = None  # the first line not read, past MAX_READ_BYTES
    size: int = 0  # the file's size in bytes

    @property
    def message(self) -> str | None:
        """One sentence on whatever was wrong with the file (None when nothing was)."""
        parts = []
        foreign = ", ".join(str(v) for v in sorted(v for v in self.versions if v is not None))
        if foreign:
            parts.append(f"it was written in recording format version {foreign} and this tui-gym "
                         f"reads version {FORMAT_VERSION}")
        elif None in self.versions:
            parts.append(f"its header names no format version this tui-gym reads "
                         f"(version {FORMAT_VERSION})")
        if self.missing_header:
            parts.append("it does not start with a recording header")
        if self.cut_at_line is not None:
            parts.append(f"it is {self.size / 2**20:,.0f} MB and only its first "
                         f"{MAX_READ_BYTES >> 20} MB (up to line {self.cut_at_line - 1:,}) "
                         "are read")
        if self.unfit_scenes:
            one = self.unfit_scenes == 1
            parts.append(f"{self.unfit_scenes:,} scene{'' if one else 's'} did not fit "
                         f"{'its game and is' if one else 'their game and are'} not drawn")
        if self.skipped:
            count = len(self.skipped)
            named = ", ".join(str(n) for n in self.skipped[:LINES_NAMED])
            more = f" and {count - LINES_NAMED} more" if count > LINES_NAMED else ""
            noun = "line" if count == 1 else "lines"
            parts.append(f"{count} {noun} could not be read and {'was' if count == 1 else 'were'}"
                         f" skipped ({noun} {named}{more})")
        if not parts:
            return None
        rest = "what was read" if self.cut_at_line is not None else "the rest"
        return f"{visible(self.path.name)}: " + "; ".join(parts) + f"; {rest} replays."


def read_recording(path: str | Path, scene_fits: SceneCheck | None = None) -> Recording:
    """Read a recording; RecordingError when it cannot be opened or holds no episode.
    `scene_fits(board, scene)`, when given, says which scenes can be drawn."""
    path = Path(path)
    if path.is_dir():
        raise RecordingError(f"{path}: is a folder, not a recording")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0)
    try:  # non-blocking: a named pipe with no writer is refused, not waited on
        handle = os.fdopen(os.open(path, flags), "rb")
    except FileNotFoundError:
        raise RecordingError(f"{path}: no such file") from None
    except OSError as exc:
        raise RecordingError(f"{path}: cannot read ({exc.strerror or exc})") from None
    with handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise RecordingError(f"{path} is not a regular file (a pipe or a device), "
                                 "not a recording")
        recording = Recording(path)
        reader = _Reader(recording, scene_fits)
        read = 0
        for number, line in _lines(handle):
            read += MAX_LINE_BYTES if line is None else len(line)
            if read > MAX_READ_BYTES:
                recording.cut_at_line = number
                recording.size = info.st_size
                break
            recording.lines = number
            if line is None:
                recording.skipped.append(number)
                continue
            if not line.strip():
                continue
            try:
                reader.take(number, line)
            except _Bad:
                recording.skipped.append(number)
    if not recording.episodes:
        if not recording.games and recording.skipped:
            raise RecordingError(f"{path} is not a tui-gym recording (no line of it could be read)")
        raise RecordingError(f"{path} holds no episode to replay")
    return recording


class _Bad(Exception):
    """A line that does not hold a usable record."""


def _lines(handle: IO[bytes]) -> Iterator[tuple[int, bytes | None]]:
    for number, line in enumerate(iter(lambda: handle.readline(MAX_LINE_BYTES + 1), b""), 1):
        if len(line) <= MAX_LINE_BYTES:
            yield number, line
            continue
        while line and not line.endswith(b"\n"):  # the rest of a line too long to read
            line = handle.readline(MAX_LINE_BYTES)
        yield number, None


def _constant(name: str) -> float:
    raise _Bad(f"{name} is not a JSON number")


_DECODER = json.JSONDecoder(parse_constant=_constant)  # one for every line


class _Reader:
    """Turns lines into games and episodes."""

    def __init__(self, recording: Recording, scene_fits: SceneCheck | None = None) -> None:
        self.recording = recording
        self.scene_fits = scene_fits
        self.game: RecordedGame | None = None
        self.episode: Episode | None = None
        self.last_scene: Mapping[str, Any] = {}

    def take(self, number: int, line: bytes) -> None:
        try:
            record = _DECODER.decode(line.decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError):
            raise _Bad from None
        kind = record.get("type") if isinstance(record, dict) else None
        if kind == HEADER:
            self._header(number, record)
        elif kind in (START, STEP, END):
            getattr(self, f"_{kind}")(_int(record.get("episode")), record)  # _start, _step, _end
        else:
            raise _Bad

    # --- records ---------------------------------------------------------------
    def _header(self, number: int, record: dict[str, Any]) -> None:
        version = record.get("version") if record.get("format") == FORMAT_NAME else None
        version = version if isinstance(version, int) else None
        if version != FORMAT_VERSION:
            self.recording.versions.add(version)
        wrappers = _list(record.get("wrappers"))
        if len(wrappers) > MAX_WRAPPERS:
            raise _Bad
        game = RecordedGame(
            line=number, version=version,
            tui_gym=_name(record.get("tui_gym")), source=_name(record.get("source")),
            game=_name(record.get("game")),
            title=_name(record.get("title")) or _name(record.get("game")) or "unknown game",
            env_id=_text(record.get("env_id")),
            env_kwargs=record["env_kwargs"] if isinstance(record.get("env_kwargs"), dict) else {},
            wrappers=tuple(visible(w, NAME_CHARS) for w in wrappers),
            seed=_optional(_int, record.get("seed")), board=_text(record.get("board")),
            actions=tuple(visible(a, NAME_CHARS) for a in _list(record.get("actions"))[:1024]),
            episode_noun=_name(record.get("episode_noun")) or "episode",
        )
        self.recording.games.append(game)
        self.game = game
        self.episode = None

    def _current_game(self) -> RecordedGame:
        if self.game is None:
            self.recording.missing_header = True
            self.game = UNKNOWN_GAME
        return self.game

    def _start(self, number: int, record: dict[str, Any]) -> None:
        frame = self._frame(record)
        self._open(seed=_optional(_int, record.get("seed")), positions=[Position(frame, None)],
                   recorded_number=number)

    def _open(self, **fields: Any) -> Episode:
        """A new episode of the current game, the one moves now go to."""
        episode = Episode(index=len(self.recording.episodes) + 1, game=self._current_game(),
                          **fields)
        self.recording.episodes.append(episode)
        self.episode = episode
        return episode

    def _step(self, number: int, record: dict[str, Any]) -> None:
        game = self._current_game()
        action = _int(record.get("action"))
        verdict = record.get("verdict")
        if verdict is not None and verdict not in VERDICTS:
            raise _Bad
        name = _name(record.get("action_name"))
        move = Move(
            step=_int(record.get("step")), action=action,
            action_name=name or game.action_name(action), reward=_number(record.get("reward")),
            terminated=_bool(record.get("terminated")), truncated=_bool(record.get("truncated")),
            verdict=verdict, regret=_optional(_number, record.get("regret")),
            optimal=tuple(visible(a, NAME_CHARS) for a in _list(record.get("optimal"))[:64]),
            note=_words(record.get("note")),
        )
        frame = self._frame(record)
        episode = self.episode
        if episode is None or episode.recorded_number != number or episode.end is not None:
            # Its start line was lost: the episode begins at this move.
            episode = self._open(started=False, recorded_number=number)
        episode.positions.append(Position(frame, move))

    def _end(self, number: int, record: dict[str, Any]) -> None:
        end = EpisodeEnd(
            steps=_int(record.get("steps")), episode_return=_number(record.get("return")),
            terminated=_bool(record.get("terminated")), truncated=_bool(record.get("truncated")),
            regret=_optional(_number, record.get("regret")),
        )
        episode = self.episode
        if episode is not None and episode.recorded_number == number and episode.end is None:
            episode.end = end
        # An end whose episode was lost altogether has nothing to replay: it is let go.

    def _frame(self, record: dict[str, Any]) -> Frame:
        scene = record.get("scene")
        if scene is not None and not isinstance(scene, dict):
            raise _Bad
        if scene is not None:
            board = self._current_game().board
            if self.scene_fits is not None and not self.scene_fits(board, scene):
                self.recording.unfit_scenes += 1
                scene = None
            else:
                scene = self._shared(scene)
        info = record.get("info")
        text = record.get("text")
        return Frame(
            observation=record.get("observation"), scene=scene,
            text=_words(text) if isinstance(text, str) else None,
            info=info if isinstance(info, dict) else {},
        )

    def _shared(self, scene: dict[str, Any]) -> dict[str, Any]:
        """`scene`, values equal to the last scene's shared with it (kept once, not per move)."""
        last = self.last_scene
        for key, value in scene.items():
            before = last.get(key)
            if before is not None and before is not value and type(before) is type(value) \
                    and before == value:
                scene[key] = before
        self.last_scene = scene
        return scene


def _int(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _Bad
    return value


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _Bad
    try:
        number = float(value)  # an integer beyond every float does not convert
    except OverflowError:
        raise _Bad from None
    if not math.isfinite(number):
        raise _Bad
    return number


def _optional(read: Callable[[Any], Any], value: Any) -> Any:
    return None if value is None else read(value)


def _bool(value: Any) -> bool:
    if not isinstance(value, bool):
        raise _Bad
    return value


def _text(value: Any) -> str:
    return value if isinstance(value, str) else ""


def _name(value: Any) -> str:
    """A name from the file as it may be shown: control characters visible, cut short."""
    return visible(value, NAME_CHARS) if isinstance(value, str) else ""


def _words(value: Any) -> str:
    """Text from the file as it may be shown, line by line (see `_name`)."""
    if not isinstance(value, str):
        return ""
    lines = value.split("\n")
    shown = [visible(line, TEXT_CHARS) for line in lines[:TEXT_LINES]]
    if len(lines) > TEXT_LINES:
        shown.append(f"… ({len(lines):,} lines)")
    return "\n".join(shown)


def _list(value: Any) -> Sequence[Any]:
    return value if isinstance(value, list) else ()
