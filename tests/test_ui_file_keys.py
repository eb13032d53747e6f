"""The save and load keys are where a person looks for them: the README here; the help
screen and the command palette's "Save agent…" and "Load agent…", which open the
file dialog, in the app's save test (test_ui_files.py)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_the_readme_names_the_save_and_load_keys() -> None:
    text = " ".join((REPO / "README.md").read_text(encoding="utf-8").split())
    assert "`ctrl+s` save the agent, `ctrl+o` load one" in text  # the key table
    assert "`ctrl+s` saves the agent to a file you name" in text
    assert "`ctrl+o` loads one" in text and "both are in the command palette too" in text
