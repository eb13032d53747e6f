"""Widgets of the tui-gym app, one a file; the game boards' registry is `board_kinds`."""
