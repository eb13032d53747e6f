"""`tui-gym benchmark`: a player against the exact optimum on fixed seeds."""
