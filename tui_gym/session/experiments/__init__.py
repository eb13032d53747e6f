"""Experiments above sessions: comparisons and sweeps of learners across seeds, and what
records a train run or the app's runs into the run history (`tui_gym.core.experiments`)."""
