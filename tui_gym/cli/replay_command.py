"""`--record PATH` for the commands that play, and the `replay` command."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from rich.console import Console

from tui_gym.cli.flags import output_file
from tui_gym.cli.output import CliError, cli_errors, warn

if TYPE_CHECKING:
    from tui_gym.core.recording import Recording
    from tui_gym.session.recording.recorder import Recorder
    from tui_gym.session.session import Session

RECORD_HELP = "record every episode to this file, as JSON lines (tui-gym replay PATH plays it back)"


def add_record_option(parser: argparse.ArgumentParser) -> None:
    """`--record PATH` on `parser`."""
    parser.add_argument("--record", type=output_file, metavar="PATH", help=RECORD_HELP)


def open_recorder(path: str, session: Session, *, source: str, seed: int | None = None) -> Recorder:
    """A `Recorder` writing `session`'s episodes to `path`; CliError when it cannot be opened
    (a write that fails later stops the recording with one line on stderr)."""
    from tui_gym.session.recording.recorder import Recorder

    try:
        return Recorder(path, session, source=source, seed=seed, on_failure=warn)
    except IsADirectoryError:
        raise CliError(f"--record {path}: is a folder; name a file") from None
    except OSError as exc:
        raise CliError(f"--record {path}: cannot write ({exc.strerror or exc})") from None


def add_replay_parser(sub: Any) -> None:
    """The `replay` sub-command."""
    replay = sub.add_parser(
        "replay", help="step through a recording in the app (tui-gym --record / play --record)"
    )
    replay.add_argument("path", metavar="PATH", help="a recording (JSON lines)")


def cmd_replay(args: argparse.Namespace, out: Console) -> int:
    from tui_gym.core.recording import RecordingError, read_recording
    from tui_gym.session.recording.scenes import scene_fits

    with cli_errors(RecordingError):
        recording = read_recording(args.path, scene_fits)
    from tui_gym.ui.app import run_app

    return run_app(session=session_for(recording), replay=recording, runner=args.runner)


def session_for(recording: Recording) -> Session | None:
    """A session on the game of the recording's first episode (None when it cannot be built:
    the app then opens on its default game, and the replay shows what was recorded);
    CliError when its id would import a module."""
    from tui_gym.core.wrappers import parse_wrapper_spec
    from tui_gym.games import ImportRefusedError, resolve_env_id
    from tui_gym.session.session import Session

    game = recording.episodes[0].game
    try:
        env_id = resolve_env_id(game.env_id, from_data=True)
    except ImportRefusedError as error:
        raise CliError(f"{recording.path}: {error}") from None
    except ValueError:
        return None
    try:
        return Session(
            env_id=env_id, env_kwargs=dict(game.env_kwargs),
            choices=tuple(parse_wrapper_spec(spec) for spec in game.wrappers), seed=game.seed or 0,
        )
    except Exception:  # another version's game or wrapper: replay needs none of it
        return None
