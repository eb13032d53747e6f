"""A file a command reads that is not there, or is a folder, is said in the same words
by every command."""

from __future__ import annotations

from pathlib import Path

import pytest

from tui_gym.cli import main

READERS = {  # the command line reading FILE, and the flag its message names first
    "eval": (["eval", "FILE"], ""),
    "replay": (["replay", "FILE"], ""),
    "benchmark --agent": (["benchmark", "blackjack", "--agent", "FILE"], ""),
    "maps --check": (["maps", "--check", "FILE"], ""),
    "plan --policy": (["plan", "frozenlake", "--policy", "FILE"], ""),
    "--map-file": (["optimal", "frozenlake", "--map-file", "FILE"], "--map-file "),
    "--follow": (["train", "blackjack", "--algorithm", "td0", "--follow", "FILE"], "--follow: "),
}


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_missing_file_is_no_such_file(
    reader: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, flag = READERS[reader]
    missing = tmp_path / "none.txt"
    assert main([str(missing) if word == "FILE" else word for word in argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == f"tui-gym: error: {flag}{missing}: no such file\n"


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_folder_is_said_to_be_one(
    reader: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, flag = READERS[reader]
    assert main([str(tmp_path) if word == "FILE" else word for word in argv]) == 2
    assert capsys.readouterr().err.startswith(f"tui-gym: error: {flag}{tmp_path}: is a folder")
