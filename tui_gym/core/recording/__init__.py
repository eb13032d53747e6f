"""Recorded episodes: a JSON-lines format, its writer and a tolerant reader, and the coach's
judgement of each move. What records (`Recorder`) is in `tui_gym.session.recording`.

- `format`: the record types and their fields, `FORMAT_VERSION`;
- `writer`: `LineWriter`, whole lines only, each flushed as it is written;
- `judge`: `MoveJudge`, the verdict and exact regret of a move;
- `reader`: `read_recording`, episodes back for replay, bad lines skipped and counted.
"""

from tui_gym.core.recording.format import FORMAT_NAME, FORMAT_VERSION
from tui_gym.core.recording.judge import Assessment, Judgement, MoveJudge
from tui_gym.core.recording.reader import (
    Episode,
    Frame,
    Move,
    Position,
    RecordedGame,
    Recording,
    RecordingError,
    read_recording,
)

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "Assessment",
    "Episode",
    "Frame",
    "Judgement",
    "Move",
    "MoveJudge",
    "Position",
    "RecordedGame",
    "Recording",
    "RecordingError",
    "read_recording",
]
