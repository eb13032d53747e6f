"""Recorded episodes: the JSON-lines format, its writer and reader, the judge of each move."""

from tui_gym.core.recording.format import FORMAT_VERSION
from tui_gym.core.recording.judge import MoveJudge
from tui_gym.core.recording.reader import Recording, RecordingError, read_recording

__all__ = ["FORMAT_VERSION", "MoveJudge", "Recording", "RecordingError", "read_recording"]
