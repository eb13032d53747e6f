"""`RecordingSwitch`: recording that a person turns on and off while playing."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from tui_gym.session.play import HumanGame
    from tui_gym.session.recording.recorder import Recorder


class RecordingSwitch:
    """Records a person's games while on; `path` is the file it writes (or will)."""

    def __init__(
        self, path: str | Path | None = None, *, source: str = "app",
        on_failure: Callable[[str], None] | None = None,
    ) -> None:
        self.path = Path(path) if path is not None else None
        self.source = source
        self.on_failure = on_failure
        self.recorder: Recorder | None = None
        self._used = False  # the file has been written once: later turns add to it

    @property
    def on(self) -> bool:
        return self.recorder is not None and self.recorder.active

    def turn_on(self, game: HumanGame) -> Path:
        """Start recording `game` (OSError when the file cannot be opened); the file's path."""
        from tui_gym.core.recording.format import SUFFIX
        from tui_gym.session.recording.recorder import Recorder  # most runs never record

        if self.on:
            assert self.path is not None
            return self.path
        stamp = time.strftime("%Y%m%d-%H%M%S")  # tui-gym-blackjack-20250101-120000.jsonl
        path = self.path or Path.cwd() / f"tui-gym-{game.game.name}-{stamp}{SUFFIX}"
        self.recorder = Recorder(path, game.session, source=self.source, seed=game.seed,
                                 append=self._used, on_failure=self._failed)
        self.path, self._used = path, True
        last = game.last
        if last is not None and last.steps == 0 and not last.done:
            self.recorder.game_reset(game)  # no move made yet: this episode is recorded whole
        return path

    def turn_off(self) -> Path | None:
        """Stop recording (an unfinished episode ends as abandoned); the file, if one was on."""
        recorder, self.recorder = self.recorder, None
        if recorder is None:
            return None
        recorder.close()
        return recorder.path

    def _failed(self, message: str) -> None:
        self.recorder = None
        if self.on_failure is not None:
            self.on_failure(message)

    # --- what a HumanGame calls ------------------------------------------------
    def game_reset(self, game: HumanGame, seed: int | None = None) -> None:
        if self.recorder is not None:
            self.recorder.game_reset(game, seed)

    def game_step(self, game: HumanGame) -> None:
        if self.recorder is not None:
            self.recorder.game_step(game)
