"""The run history's errors: each message is one line naming the file and what is wrong."""

from __future__ import annotations


class RunHistoryError(Exception):
    """Anything wrong with the run history; the message names the file."""


class NotARunHistoryError(RunHistoryError):
    """The file is not a tui-gym run history (not SQLite, or another program's)."""


class DamagedRunHistoryError(RunHistoryError):
    """The file is a run history SQLite cannot read through; `runs --recover` may save runs."""


class NewerRunHistoryError(RunHistoryError):
    """The file was made by a newer tui-gym, with a schema this one does not know."""


class RunHistoryBusyError(RunHistoryError):
    """Another process held the file's write lock for too long."""


class UnknownRunError(RunHistoryError, LookupError):
    """No run has that id."""


class DamagedRunError(RunHistoryError):
    """One run's row does not read as a run (an edit, damage); the others are readable."""

    def __init__(self, run_id: int, message: str) -> None:
        super().__init__(message)
        self.run_id = run_id
