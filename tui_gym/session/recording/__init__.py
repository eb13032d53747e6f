"""Recording games as they are played: `Recorder` (what `play`, `benchmark` and the app
record with) and the switch the app turns recording on and off with. The file format, the
reader and the judge of each move are in `tui_gym.core.recording`."""

from tui_gym.session.recording.recorder import Recorder

__all__ = ["Recorder"]
