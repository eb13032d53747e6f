"""The `tui-gym` command."""

from tui_gym.cli.main import attach_negative_values, build_parser, main

__all__ = ["attach_negative_values", "build_parser", "main"]
