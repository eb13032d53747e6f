"""`tui-gym mcp` through the MCP SDK's own client over stdio: every game played to the
end, bad calls refused with a clear message, `--no-hints`, the bound on games, and idle
games expiring (on an injected clock, through the SDK's in-process client)."""

from __future__ import annotations

import importlib.util
import math
import sys
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING

import pytest

from tui_gym.session.arena import GameTable, catalog

if TYPE_CHECKING:
    from tests.mcp_support import McpInProcess, McpProcess

if importlib.util.find_spec("mcp") is None:
    pytest.skip("the mcp extra is not installed", allow_module_level=True)
# One worker runs this module, so each server process below starts once. The SDK loads
# with the first test: the workers that run none of these do not load it to collect them.
pytestmark = pytest.mark.xdist_group("mcp_server")

GAMES = [entry.name for entry in catalog()]
IDLE_SECONDS = 5.0  # the no-hints server's idle timeout
POLL_SECONDS = 0.1


def in_process_client(table: GameTable) -> McpInProcess:
    """The SDK's in-process client of a server over `table`."""
    from tests.mcp_support import McpInProcess
    from tui_gym.mcp_server.server import build_server

    return McpInProcess(build_server(table))


def stdio_server(*args: str) -> McpProcess:
    """`python -m tui_gym mcp ARGS`, through the SDK's client over stdio."""
    from tests.mcp_support import McpProcess

    return McpProcess(*args)


@pytest.fixture(scope="module")
def server() -> Iterator[McpProcess]:
    process = stdio_server("--max-games", "3")
    yield process
    process.close()
    assert "Traceback" not in process.stderr_text()


@pytest.fixture(scope="module")
def no_hints() -> Iterator[McpProcess]:
    """The server its tests share: calls come within milliseconds of each other, far
    inside the idle timeout that the expiry test waits out."""
    process = stdio_server("--no-hints", "--max-games", "2",
                           "--idle-timeout", str(IDLE_SECONDS))
    yield process
    process.close()
    assert "Traceback" not in process.stderr_text()


def test_the_tools_and_the_games_they_list(server: McpProcess) -> None:
    assert set(server.tools()) >= {
        "list_games", "start_game", "observe", "step", "hint", "score", "reset", "end_game"
    }
    listed = server.data("list_games")
    assert [g["name"] for g in listed["games"]] == GAMES
    for game, entry in zip(listed["games"], catalog(), strict=True):
        assert game["actions"] == list(entry.actions)
        assert [p["name"] for p in game["parameters"]] == [p.name for p in entry.params]
    assert listed["max_games"] == 3 and listed["hints"] is True


@pytest.mark.parametrize("game", GAMES)
def test_a_whole_episode_of_every_game_played_optimally(server: McpProcess, game: str) -> None:
    start = server.data("start_game", game=game, seed=5)
    game_id = start["game_id"]
    assert start["game"] == game and start["done"] is False and start["text"]
    assert start["legal_actions"]
    try:
        for _ in range(1000):
            hint = server.data("hint", game_id=game_id)
            move = server.data("step", game_id=game_id, action=hint["optimal_actions"][0])
            assert move["verdict"]["decision"] is True and move["verdict"]["optimal"] is True
            if move["done"]:
                break
        observed = server.data("observe", game_id=game_id)
        assert observed["done"] is True and observed["legal_actions"] == []
        score = server.data("score", game_id=game_id)
        assert score["episodes"] == 1 and score["decisions"] >= 1 and score["agreement"] == 1.0
        assert score["recent_episodes"][0]["return"] == pytest.approx(observed["episode_return"])
        assert score["recent_episodes"][0]["seed"] == 5
        if "action_values" in hint:  # exact values: an optimal episode loses nothing
            assert score["regret"]["mean_per_episode"] == pytest.approx(0.0, abs=1e-12)
        else:
            assert score["regret"]["mean_per_episode"] is None
            assert "no exact action values" in score["regret"]["note"]
    finally:
        server.data("end_game", game_id=game_id)


def test_a_costly_move_is_scored_by_its_exact_regret(server: McpProcess) -> None:
    game_id = server.data("start_game", game="blackjack", seed=7)["game_id"]
    try:
        values = server.data("hint", game_id=game_id)["action_values"]
        move = server.data("step", game_id=game_id, action=1)  # hit on 19 against a 10
        regret = values["stick"] - values["hit"]
        assert regret > 0.5
        assert move["verdict"] == {"decision": True, "optimal": False,
                                   "optimal_actions": ["stick"], "regret": regret}
        score = server.data("score", game_id=game_id)
        assert score["regret"]["mean_per_episode"] == pytest.approx(regret)
        assert score["agreement"] == 0.0 and score["mean_return"] == -1.0
        again = server.data("reset", game_id=game_id, seed=7)
        assert again["observation"] == [19, 10, 0] and again["episode"] == 2
    finally:
        server.data("end_game", game_id=game_id)


def test_bad_calls_get_clear_errors_and_the_server_goes_on(server: McpProcess) -> None:
    unknown = server.error("start_game", game="chess")
    assert "'chess'" in unknown and "blackjack" in unknown  # the games it knows
    assert "out of range" in server.error("start_game", game="gridworld", parameters={"size": 99})
    assert "not 'colour'" in server.error(
        "start_game", game="gridworld", parameters={"colour": 1}
    )
    assert "unknown wrapper" in server.error(
        "start_game", game="blackjack", wrappers=["NoSuchWrapper"]
    ).lower()
    assert "no game 999" in server.error("observe", game_id=999)
    assert "game_id" in server.error("step", game_id="seven", action=0)
    assert "Unknown tool" in server.error("fly", game_id=1)
    game_id = server.data("start_game", game="blackjack", seed=7)["game_id"]
    try:
        assert "valid actions: 0=stick, 1=hit" in server.error("step", game_id=game_id, action=7)
        assert "valid actions" in server.error("step", game_id=game_id, action="double")
        server.data("step", game_id=game_id, action="stick")
        assert "the episode is over" in server.error("step", game_id=game_id, action="stick")
        assert "the episode is over" in server.error("hint", game_id=game_id)
        assert server.data("observe", game_id=game_id)["done"] is True
    finally:
        server.data("end_game", game_id=game_id)
    assert "was ended" in server.error("score", game_id=game_id)


def test_no_hints_refuses_the_hint_and_hides_verdicts(no_hints: McpProcess) -> None:
    assert no_hints.data("list_games")["hints"] is False
    game_id = no_hints.data("start_game", game="blackjack", seed=7)["game_id"]
    try:
        assert "hints are off" in no_hints.error("hint", game_id=game_id)
        move = no_hints.data("step", game_id=game_id, action="hit")
        assert "verdict" not in move and move["done"] is True
        score = no_hints.data("score", game_id=game_id)
        assert score["regret"]["mean_per_episode"] > 0.5  # still scored, after the episode
        no_hints.data("reset", game_id=game_id)
        assert "current_episode" not in no_hints.data("score", game_id=game_id)
    finally:
        no_hints.data("end_game", game_id=game_id)


def test_the_number_of_games_is_bounded(no_hints: McpProcess) -> None:
    first = no_hints.data("start_game", game="blackjack")["game_id"]
    second = no_hints.data("start_game", game="gridworld")["game_id"]
    refused = no_hints.error("start_game", game="blackjack")
    assert "2 games are running, the most this server plays at once" in refused
    no_hints.data("end_game", game_id=first)
    third = no_hints.data("start_game", game="blackjack")["game_id"]
    assert third > second
    for game_id in (second, third):
        no_hints.data("end_game", game_id=game_id)


def test_an_idle_game_expires_over_stdio(no_hints: McpProcess) -> None:
    idle = no_hints.data("start_game", game="blackjack", seed=1)["game_id"]
    filler = no_hints.data("start_game", game="gridworld", seed=1)["game_id"]
    used = time.monotonic()  # the server last used either game before this
    refused = no_hints.error("start_game", game="gridworld", seed=1)
    assert "the most this server plays at once" in refused
    # Both expire IDLE_SECONDS after their last use (the filler a call later than the
    # other): wait that out, then a place frees at the next call.
    time.sleep(max(0.0, used + IDLE_SECONDS - time.monotonic()))
    deadline = time.monotonic() + 30
    while True:
        result = no_hints.call("start_game", game="gridworld", seed=1)
        if not result.is_error:
            break
        assert "the most this server plays at once" in result.content[0].text
        assert time.monotonic() < deadline, "the idle games never expired"
        time.sleep(POLL_SECONDS)
    for game_id in (idle, filler):
        message = no_hints.error("observe", game_id=game_id)
        assert f"expired after {IDLE_SECONDS:g} s without a call" in message
    no_hints.data("end_game", game_id=result.structured_content["game_id"])


def test_idle_games_expire_on_the_tables_clock() -> None:
    now = [0.0]
    table = GameTable(max_games=1, idle_timeout=60, clock=lambda: now[0])
    client = in_process_client(table)
    try:
        game_id = client.data("start_game", game="blackjack", seed=1)["game_id"]
        now[0] = 59.0
        client.data("observe", game_id=game_id)  # a call keeps it alive
        assert "the most this server plays" in client.error("start_game", game="gridworld")
        now[0] = 59.0 + 60.5
        other = client.data("start_game", game="gridworld")["game_id"]
        assert f"game {game_id} expired after 60 s without a call" in client.error(
            "step", game_id=game_id, action=0
        )
        assert len(table) == 1 and table.ids() == [other]
    finally:
        client.close()
        table.close()


def test_without_the_sdk_the_command_says_how_to_install_it(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from tui_gym.cli import main

    for name in {"mcp", *[n for n in sys.modules if n.startswith("mcp.")]}:
        monkeypatch.setitem(sys.modules, name, None)  # as if not installed
    monkeypatch.delitem(sys.modules, "tui_gym.mcp_server.server", raising=False)
    assert main(["mcp"]) == 2
    assert capsys.readouterr() == ("", "tui-gym mcp needs the MCP SDK: pip install "
                                       "'tui-gym[mcp]'\n")


def test_scores_stay_finite_json(server: McpProcess) -> None:
    game_id = server.data("start_game", game="gridworld", seed=1)["game_id"]
    try:
        score = server.data("score", game_id=game_id)
        assert score["episodes"] == 0 and score["mean_return"] is None
        assert not any(isinstance(v, float) and not math.isfinite(v) for v in score.values())
    finally:
        server.data("end_game", game_id=game_id)


@pytest.fixture(scope="module")
def in_process() -> Iterator[McpInProcess]:
    table = GameTable(max_games=2)
    client = in_process_client(table)
    yield client
    client.close()
    table.close()


@pytest.mark.parametrize(("tool", "arguments", "argument", "takes"), [
    ("step", {"action": True}, "action", "an action's name or number, not True"),
    ("step", {"action": 1.5}, "action", "an action's name or number, not 1.5"),
    ("step", {"game_id": "seven", "action": 0}, "game_id", "the id start_game returned"),
    ("step", {"game_id": True, "action": 0}, "game_id", "the id start_game returned"),
    ("step", {"action": 0, "game_id": None}, "game_id", "the id start_game returned"),
    ("observe", {}, "game_id", "is missing (the id start_game returned)"),
    ("start_game", {"game": "blackjack", "seed": -1}, "seed", "a whole number >= 0"),
    ("start_game", {"game": 7}, "game", "a game name from list_games"),
    ("start_game", {"game": "blackjack", "wrappers": "TimeLimit"}, "wrappers", "a list of"),
])
def test_an_argument_of_the_wrong_type_is_named_in_one_line(
    in_process: McpInProcess, tool: str, arguments: dict[str, object], argument: str,
    takes: str,
) -> None:
    game_id = in_process.data("start_game", game="blackjack", seed=1)["game_id"]
    try:
        message = in_process.error(tool, **{"game_id": game_id, **arguments}
                                   if tool == "step" else arguments)
    finally:
        in_process.data("end_game", game_id=game_id)
    assert message.startswith(f"Error executing tool {tool}: argument {argument} "), message
    assert takes in message and "\n" not in message and "http" not in message, message


def test_a_bool_is_not_an_action(in_process: McpInProcess) -> None:
    game_id = in_process.data("start_game", game="blackjack", seed=3)["game_id"]
    try:
        in_process.error("step", game_id=game_id, action=True)
        assert in_process.data("observe", game_id=game_id)["steps"] == 0  # nothing was played
    finally:
        in_process.data("end_game", game_id=game_id)


def test_huge_or_deep_calls_are_answered_in_short(in_process: McpInProcess) -> None:
    name = in_process.error("start_game", game="x" * 5_000_000)
    assert "5,000,000 characters" in name and len(name) < 300
    chain = in_process.error("start_game", game="blackjack",
                             wrappers=["DelayObservation"] * 2_000)
    assert "a chain of 2,000 wrappers: a chain holds at most 32" in chain
    for call in ({"parameters": {"k" * 100_000: 1}}, {"wrappers": ["W" * 100_000]}):
        message = in_process.error("start_game", game="blackjack", **call)
        assert "100,000 characters" in message and len(message) < 400, message
