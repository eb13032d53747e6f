"""Recorded episodes: a JSON-lines format, its writer and tolerant reader, and the coach's
judgement of each move."""

from tui_gym.core.recording.format import FORMAT_VERSION
from tui_gym.core.recording.judge import MoveJudge
from tui_gym.core.recording.reader import Recording, RecordingError, read_recording

__all__ = ["FORMAT_VERSION", "MoveJudge", "Recording", "RecordingError", "read_recording"]
