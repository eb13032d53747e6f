"""Recorded episodes: a JSON-lines format, its writer and a tolerant reader, and the coach's
judgement of each move. What records (`Recorder`) is in `tui_gym.session.recording`.
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
    "FORMAT_NAME", "FORMAT_VERSION", "Assessment", "Episode", "Frame", "Judgement", "Move",
    "MoveJudge", "Position", "RecordedGame", "Recording", "RecordingError", "read_recording",
]
