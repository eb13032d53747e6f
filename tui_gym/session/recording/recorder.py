"""`Recorder`: writes the episodes a player plays to a recording file (see `format`)."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from tui_gym import __version__
from tui_gym.core.recording.format import (
    END,
    FORMAT_NAME,
    FORMAT_VERSION,
    HEADER,
    START,
    STEP,
    encode_line,
)
from tui_gym.core.recording.judge import NOTHING_KNOWN, Assessment, MoveJudge
from tui_gym.core.recording.writer import LineWriter

if TYPE_CHECKING:
    from tui_gym.session.play import HumanGame
    from tui_gym.session.session import Session


class GameRecorder(Protocol):
    """What a `HumanGame` tells of its play: a `Recorder` or a `RecordingSwitch`."""

    def game_reset(self, game: HumanGame, seed: int | None = None) -> None: ...

    def game_step(self, game: HumanGame) -> None: ...


@dataclass
class _Episode:
    """The episode being written."""

    number: int
    steps: int = 0
    total: float = 0.0
    regret: float | None = 0.0  # None once a move's regret was unknown
    terminated: bool = False
    truncated: bool = False
    pending: Assessment = NOTHING_KNOWN  # the optimum's view of the state reached


class Recorder:
    """Records episodes of one session's game (or several, in turn) as JSON lines."""

    def __init__(
        self, path: str | Path, session: Session | None = None, *, source: str = "play",
        seed: int | None = None, append: bool = False,
        on_failure: Callable[[str], None] | None = None,
    ) -> None:
        """Open `path` (emptied unless `append`; OSError if not) and write `session`'s header."""
        self.path = Path(path)
        self.source = source
        self.seed = seed
        self.on_failure = on_failure
        self.failure: str | None = None
        self.episodes = 0  # episodes started in this file by this recorder
        self._writer: LineWriter | None = LineWriter(self.path, truncate=not append)
        self._header_key: tuple[Any, ...] | None = None
        self._played: Any = None
        self._judge: MoveJudge  # set with the header (`use_session`)
        self._episode: _Episode | None = None
        self._game: HumanGame | None = None  # whose episode is open (`game_reset`)
        if session is not None:
            self.use_session(session)

    # --- state ---------------------------------------------------------------
    @property
    def active(self) -> bool:
        """Still writing: neither closed nor stopped by a failed write."""
        return self._writer is not None

    @property
    def episode_open(self) -> bool:
        return self._episode is not None

    # --- the calls -------------------------------------------------------------
    def use_session(self, session: Session) -> None:
        """Record the session's game from here on: a new header when it differs from the last."""
        from tui_gym.core.wrappers import format_wrapper_spec

        key = (session.env_id, tuple(sorted((k, repr(v)) for k, v in session.env_kwargs.items())),
               tuple(session.applied))
        self._played = game = session.game
        if key == self._header_key:
            return
        self.end_episode()
        self._header_key = key
        self._judge = MoveJudge(game, session.env_kwargs)
        self._write({
            "type": HEADER, "format": FORMAT_NAME, "version": FORMAT_VERSION,
            "tui_gym": __version__, "source": self.source, "game": game.name, "title": game.title,
            "env_id": session.env_id, "env_kwargs": dict(session.env_kwargs),
            "wrappers": [format_wrapper_spec(choice) for choice in session.applied],
            "seed": self.seed, "board": game.board, "actions": list(game.action_names),
            "episode_noun": game.episode_noun,
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        })

    def end_episode(self) -> None:
        """Write the open episode's end line (nothing when none is open)."""
        episode, self._episode = self._episode, None
        self._game = None
        if episode is None:
            return
        self._write({
            "type": END, "episode": episode.number, "steps": episode.steps, "return": episode.total,
            "terminated": episode.terminated, "truncated": episode.truncated,
            "regret": episode.regret,
        })

    def close(self) -> None:
        """End the open episode (abandoned when unfinished) and close the file."""
        self.end_episode()
        if self._writer is not None:
            writer, self._writer = self._writer, None
            writer.close()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- what a HumanGame calls ------------------------------------------------
    def game_reset(self, game: HumanGame, seed: int | None = None) -> None:
        """`game` was just reset (with `seed`, if given): a new episode, an open one abandoned."""
        last = game.last
        if last is None or not self.active:
            return
        self.use_session(game.session)
        self.end_episode()
        self.episodes += 1
        episode = self._episode = _Episode(self.episodes)
        record: dict[str, Any] = {"type": START, "episode": episode.number}
        if seed is not None:
            record["seed"] = seed
        self._write({**record, **self._state(game.env, last.observation, last.info)})
        episode.pending = self._judge.assess(game.env)
        self._game = game

    def game_step(self, game: HumanGame) -> None:
        """`game` has just made a move: recorded with the coach's judgement."""
        last, episode = game.last, self._episode
        if last is None or last.action is None or episode is None or game is not self._game:
            return  # an episode whose start this recording did not see
        action = int(last.action)
        judgement = episode.pending.judge(action)
        episode.steps += 1
        episode.total += last.reward
        if episode.regret is not None:
            episode.regret = None if judgement.regret is None else episode.regret + judgement.regret
        episode.terminated, episode.truncated = last.terminated, last.truncated
        names = self._played.action_names
        self._write({
            "type": STEP, "episode": episode.number, "step": episode.steps, "action": action,
            "action_name": names[action] if 0 <= action < len(names) else str(action),
            "reward": last.reward, "terminated": episode.terminated,
            "truncated": episode.truncated, **self._state(game.env, last.observation, last.info),
            "verdict": judgement.verdict, "regret": judgement.regret,
            "optimal": [names[a] for a in judgement.optimal if 0 <= a < len(names)],
        })
        if last.done:
            self.end_episode()
        else:
            episode.pending = self._judge.assess(game.env)

    # --- helpers ---------------------------------------------------------------
    def _state(self, env: Any, observation: Any, info: Mapping[str, Any] | None) -> dict[str, Any]:
        """The observation, the scene and the state in words (None for each that fails)."""
        states = self._played.states
        parts: dict[str, tuple[Callable[[Any], Any], Any]] = {
            "observation": (states.json_observation, observation),
            "scene": (states.scene, env), "text": (states.describe, observation)}
        state: dict[str, Any] = {}
        for name, (make, given) in parts.items():
            try:
                state[name] = make(given)
            except Exception:
                state[name] = None
        return {**state, "info": dict(info or {})}

    def _write(self, record: dict[str, Any]) -> None:
        writer = self._writer
        if writer is None:
            return
        try:
            writer.write(encode_line(record))
        except (OSError, ValueError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            self.failure = f"recording to {self.path} stopped: {reason}"
            self._writer = None
            with contextlib.suppress(OSError):
                writer.close()
            if self.on_failure is not None:
                self.on_failure(self.failure)
