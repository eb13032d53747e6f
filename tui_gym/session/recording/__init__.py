"""Recording games as they are played: `recorder.Recorder` (what `play`, `benchmark` and
the app record with) and `switch.RecordingSwitch`, which the app turns recording on and off
with (it imports the recorder when first turned on). The file format, the reader and the
judge of each move are in `tui_gym.core.recording`."""
