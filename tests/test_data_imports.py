"""Data never imports code: a save file, a recording or a tool call that names a
`module:Id` env is refused in one line (saying how to open it on purpose), and the
module, which would leave a marker file, never runs."""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.test_storage import _with_meta
from tui_gym.cli import main
from tui_gym.games import UnknownGameError, game_for, resolve_env_id
from tui_gym.session.session import Session
from tui_gym.session.storage import StorageError

MODULE = "tgym_marker_mod"
EVIL_ID = f"{MODULE}:FrozenLake-v1"


@pytest.fixture
def marker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A module on the import path that would write `marker` when imported."""
    folder = tmp_path / "mods"
    folder.mkdir()
    target = tmp_path / "marker"
    (folder / f"{MODULE}.py").write_text(
        f"from pathlib import Path\nPath({str(target)!r}).write_text('ran')\n"
    )
    monkeypatch.syspath_prepend(str(folder))
    monkeypatch.chdir(tmp_path)
    sys.modules.pop(MODULE, None)
    yield target
    assert not target.exists(), "the module ran"
    assert MODULE not in sys.modules


def _save_naming(tmp_path: Path, env_id: str) -> Path:
    path = tmp_path / "agent.tgym"
    Session("FrozenLake-v1", seed=0).save(path)
    path.write_bytes(_with_meta(path.read_bytes(), env_id=env_id, env_kwargs={}))
    return path


def _one_line_refusal(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "never import code" in err and f"--env {EVIL_ID}" in err, err
    return err


def test_the_data_check_refuses_a_module_id_and_keeps_registered_ones(marker: Path) -> None:
    with pytest.raises(UnknownGameError, match="never import code"):
        resolve_env_id(EVIL_ID, from_data=True)
    assert resolve_env_id("blackjack", from_data=True) == "Blackjack-v1"
    assert resolve_env_id("FrozenLake-v1", from_data=True) == "FrozenLake-v1"
    # A module imported already (the user's own --env) imports nothing more.
    assert resolve_env_id("gymnasium:CliffWalking-v1", from_data=True)


@pytest.mark.parametrize("command", [
    ["eval", "agent.tgym"],
    ["--load", "agent.tgym"],
    ["benchmark", "frozenlake", "--agent", "agent.tgym", "--no-record", "--episodes", "1"],
])
def test_a_save_file_naming_a_module_is_refused(
    marker: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], command: list[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import tui_gym.ui.app

    def opened(*args: object, **kwargs: object) -> None:
        raise AssertionError("the app opened")

    monkeypatch.setattr(tui_gym.ui.app.TuiGymApp, "run", opened)
    _save_naming(tmp_path, EVIL_ID)
    assert main(command) == 2
    assert "agent.tgym" in _one_line_refusal(capsys)


def test_loading_in_the_app_refuses_it_too(marker: Path, tmp_path: Path) -> None:
    with pytest.raises(StorageError, match="never import code"):
        Session.load(_save_naming(tmp_path, EVIL_ID))  # what ctrl+o calls


def test_the_users_own_env_flag_opens_it_on_purpose(
    marker: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _save_naming(tmp_path, EVIL_ID)
    assert main(["--env", EVIL_ID, "eval", "agent.tgym", "--episodes", "10", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["env_id"] == EVIL_ID
    assert marker.read_text() == "ran"
    marker.unlink()
    sys.modules.pop(MODULE)


def test_a_recording_naming_a_module_is_refused(
    marker: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import tui_gym.ui.app

    opened: list[object] = []
    monkeypatch.setattr(tui_gym.ui.app, "run_app", lambda **kw: opened.append(kw) or 0)
    lines = [
        {"type": "header", "format": "tui-gym-recording", "version": 1, "env_id": EVIL_ID,
         "board": "cards", "actions": ["stick", "hit"]},
        {"type": "start", "episode": 1, "observation": [12, 2, 0], "scene": None},
        {"type": "step", "episode": 1, "step": 1, "action": 0, "reward": 1.0,
         "terminated": True, "truncated": False, "observation": [12, 2, 0]},
    ]
    (tmp_path / "rec.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    assert main(["replay", "rec.jsonl"]) == 2
    assert "rec.jsonl" in _one_line_refusal(capsys)
    assert not opened
    with pytest.raises(UnknownGameError):  # the replay screen's words for another header
        game_for(EVIL_ID, from_data=True)


# On the worker of tests/test_mcp_server.py: the MCP SDK loads in one worker.
@pytest.mark.xdist_group("mcp_server")
def test_a_tool_call_naming_a_module_is_refused(marker: Path) -> None:
    pytest.importorskip("mcp")
    from tests.mcp_support import McpInProcess
    from tui_gym.mcp_server.server import build_server
    from tui_gym.session.arena import GameTable

    table = GameTable(max_games=2)
    client = McpInProcess(build_server(table))
    try:
        message = client.error("start_game", game=EVIL_ID)
        assert "never import code" in message and "\n" not in message
        assert client.data("start_game", game="blackjack", seed=1)["game"] == "blackjack"
    finally:
        client.close()
        table.close()
