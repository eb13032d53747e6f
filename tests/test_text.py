"""`visible`: control characters from files and programs never reach the terminal raw."""

from __future__ import annotations

from tui_gym.core.text import visible


def test_escape_sequences_and_invisible_marks_are_written_out() -> None:
    assert visible("q\x1b]2;PWNED\x1b\\") == "q\\x1b]2;PWNED\\x1b\\"
    assert visible("a\u202eb\u200bc") == "a\\u202eb\\u200bc"
    assert visible("tab\there\nline") == "tab\\x09here\\x0aline"
    assert visible("Blackjack ♠ naïve") == "Blackjack ♠ naïve"


def test_long_text_is_cut_and_says_how_long_it_was() -> None:
    shown = visible("x" * 5000, limit=20)
    assert shown.startswith("x" * 19 + "…")
    assert "5,000 characters" in shown
    assert visible("x" * 5000, limit=None) == "x" * 5000
    assert visible("\x1b" * 30, limit=20).startswith("\\x1b")
    assert len(visible("\x1b" * 30, limit=20).split("…")[0]) == 19


def test_any_object_is_shown_as_its_text() -> None:
    assert visible(12) == "12"
