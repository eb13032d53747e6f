"""`python -m tui_gym`: the same entry point as the `tui-gym` command."""

from tui_gym.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
