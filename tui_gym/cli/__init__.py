"""The `tui-gym` command.

- `main`: the entry point and the argument parser (the app with no
  sub-command);
- `flags`: the flags generated from `Param` schemas (every game's arguments,
  the hyperparameters) and how they are read for one game;
- `commands`: the headless sub-commands, each a thin call into the core;
- `output`: one-line errors, JSON objects and summary tables.
"""

from tui_gym.cli.main import attach_negative_values, build_parser, main

__all__ = ["attach_negative_values", "build_parser", "main"]
