"""Recording games as they are played: `recorder.Recorder`, and `switch.RecordingSwitch` that
the app turns on and off (the format and reader are in `tui_gym.core.recording`)."""
