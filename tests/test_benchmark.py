"""`tui-gym benchmark`: built-in players, the example program, players that misbehave,
recording in the run history and the leaderboard."""

from __future__ import annotations

import json
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tui_gym.benchmark.players import (
    AgentPlayer,
    OptimalPlayer,
    PlayerError,
    ProcessPlayer,
    RandomPlayer,
)
from tui_gym.benchmark.referee import Referee
from tui_gym.benchmark.results import run_benchmark
from tui_gym.cli import main
from tui_gym.core.mdp import optimum
from tui_gym.core.wrappers.changes import NO_CHANGES
from tui_gym.games import GAMES
from tui_gym.games.model import ModelOracle, freeze

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "heuristic_player.py"


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """`tui-gym ARGS` in this process: exit code, stdout, stderr."""
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def _script(tmp_path: Path, name: str, body: str) -> str:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return f"{sys.executable} {path}"


PLAYS_STICK = """
    import json, sys
    def ask(r):
        print(json.dumps(r), flush=True)
        return json.loads(sys.stdin.readline() or '{"error": "gone"}')
"""


def test_optimal_play_has_no_regret_and_random_play_some() -> None:
    best = run_benchmark("blackjack", OptimalPlayer(), episodes=300, seed=1)
    assert best.episodes == 300 and best.mean_regret is not None
    assert np.all(best.regrets == 0.0) and best.agreement == 1.0
    rand = run_benchmark("blackjack", RandomPlayer(1), episodes=300, seed=1)
    assert rand.mean_regret.mean > 0.2 and 0.3 < rand.agreement < 0.7
    again = run_benchmark("blackjack", RandomPlayer(1), episodes=300, seed=1)
    assert np.array_equal(again.returns, rand.returns)  # fixed seeds: the same episodes
    assert np.array_equal(again.regrets, rand.regrets)


@pytest.mark.parametrize("game", [g.name for g in GAMES])
def test_the_optimal_player_plays_a_whole_episode_of_every_game(game: str) -> None:
    result = run_benchmark(game, OptimalPlayer(), episodes=1, seed=0)
    assert result.episodes == 1 and result.decisions > 0
    if result.regrets is not None:  # games whose exact model gives action values
        assert np.all(result.regrets == 0.0) and result.agreement == 1.0


def test_the_referee_solves_the_exact_figures_before_the_first_decision_is_timed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The optimal player's hints find the exact optimum solved: the solve is the referee's
    work, not the player's thinking time (a slow solve once cost it a timeout)."""
    events: list[str] = []
    exacts: dict[tuple[object, ...], object] = {}

    def exact(self: ModelOracle, kwargs: dict[str, object], changes: object = NO_CHANGES) -> object:
        key = (id(self), freeze(kwargs), changes)  # a cache of the test's own, empty at first
        if key not in exacts:
            exacts[key] = self._build(kwargs, changes)  # type: ignore[arg-type]
        return exacts[key]

    def solving(solve: Callable[..., Any]) -> Callable[..., Any]:
        def recorded(*args: Any, **kwargs: Any) -> Any:
            events.append("solve")
            return solve(*args, **kwargs)
        return recorded

    class Watched(OptimalPlayer):
        def choose(self, referee: Referee) -> str:
            events.append("choose")
            return super().choose(referee)

    monkeypatch.setattr(ModelOracle, "exact", exact)
    for name in ("_induction", "solve"):  # how the optimum's ladder solves its rungs
        monkeypatch.setattr(optimum, name, solving(getattr(optimum, name)))
    result = run_benchmark("car-rental", Watched(), episodes=1, seed=0)
    assert "solve" in events and "solve" not in events[events.index("choose"):]
    assert result.fouls.timeouts == 0 and np.all(result.regrets == 0.0)


def test_the_example_player_through_the_cli_and_the_leaderboard(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = str(tmp_path / "runs.db")
    code, out, err = _cli(capsys, "benchmark", "blackjack", "--agent-cmd",
                          f"{sys.executable} {EXAMPLE}", "--episodes", "300", "--seed", "3",
                          "--json", "--db", db, "--name", "stick on 17")
    assert code == 0, err
    result = json.loads(out)
    assert result["episodes"] == 300 and result["seeds"] == [3, 302]
    assert result["invalid_actions"] == result["timeouts"] == result["bad_requests"] == 0
    assert 0 < result["mean_regret"] < 0.1 and 0.7 < result["agreement"] < 1.0
    assert result["player_status"] == "played every episode; exited with code 0"
    assert result["decision_ms_median"] > 0 and result["run_id"] == 1
    assert result["player"] == "stick on 17"
    code, out, _ = _cli(capsys, "benchmark", "blackjack", "--agent", "optimal", "--episodes",
                        "100", "--db", db)
    assert code == 0 and "recorded as run 2" in out
    code, out, _ = _cli(capsys, "benchmark", "--leaderboard", "blackjack", "--json", "--db", db)
    runs = json.loads(out)["runs"]
    assert [r["algorithm"] for r in runs] == ["optimal", "stick on 17"]
    assert [r["rank"] for r in runs] == [1, 2]
    code, out, _ = _cli(capsys, "benchmark", "--leaderboard", "blackjack", "--db", db)
    assert "best first" in out and "optimal" in out
    # A player's name is data: its control characters never reach the terminal.
    _cli(capsys, "benchmark", "blackjack", "--agent", "optimal", "--episodes", "20", "--db", db,
         "--name", "evil\x1b[2Jname")
    code, out, _ = _cli(capsys, "benchmark", "--leaderboard", "blackjack", "--db", db)
    assert code == 0 and "evil\\x1b[2Jname" in out and "\x1b" not in out


def test_record_writes_every_episode_of_a_benchmark(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tui_gym.core.recording import read_recording

    path = tmp_path / "bench.jsonl"
    code, _, err = _cli(capsys, "benchmark", "blackjack", "--agent", "random", "--episodes",
                        "5", "--seed", "10", "--no-record", "--record", str(path))
    assert code == 0, err
    recording = read_recording(path)
    assert recording.message is None and len(recording.episodes) == 5
    assert [e.seed for e in recording.episodes] == [10, 11, 12, 13, 14]
    with pytest.raises(SystemExit) as exit_:
        main(["benchmark", "blackjack", "--agent", "random", "--no-record", "--record",
              str(tmp_path / "no" / "such.jsonl")])
    assert exit_.value.code == 2 and "does not exist" in capsys.readouterr().err


def test_a_game_without_exact_values_says_regret_is_unavailable() -> None:
    result = run_benchmark("gridworld", ProcessPlayer(f"{sys.executable} {EXAMPLE}"),
                           episodes=2, seed=0, params={"size": 3})
    assert result.regrets is None and result.mean_regret is None
    assert "no exact action values" in result.regret_note
    assert result.player == f"{Path(sys.executable).name} heuristic_player.py"
    assert result.decisions > 0 and result.to_json()["mean_regret"] is None


def test_a_player_that_crashes_is_counted_and_the_rest_defaulted(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "crash.py", PLAYS_STICK + """
    ask({"cmd": "reset"})
    ask({"cmd": "step", "action": "stick"})
    print("something broke", file=sys.stderr)
    sys.exit(3)
    """)
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=5, seed=0)
    assert result.episodes == 5 and result.fouls.defaulted == 8  # 4 deals, 4 sticks
    assert "it exited with code 3 in episode 1 of 5" in result.status
    assert result.stderr_tail == "something broke"


def test_garbage_invalid_actions_and_hints_are_counted(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "sloppy.py", PLAYS_STICK + """
    print("hello there", flush=True); sys.stdin.readline()
    state = ask({"cmd": "reset"})
    assert "error" in ask({"cmd": "hint"})
    state = ask({"cmd": "step", "action": "double"})  # invalid: stick is played
    assert "invalid" in state and state["terminated"]
    while "error" not in ask({"cmd": "reset"}):
        ask({"cmd": "step", "action": 0})
    """)
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=3, seed=0)
    fouls = result.fouls
    assert (fouls.bad_requests, fouls.invalid_actions, fouls.hints_refused) == (1, 1, 1)
    assert result.episodes == 3 and result.status.startswith("played every episode")


def test_hints_can_be_allowed(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "hinted.py", PLAYS_STICK + """
    while "error" not in ask({"cmd": "reset"}):
        done = False
        while not done:
            best = ask({"cmd": "hint"})["optimal_actions"][0]
            done = ask({"cmd": "step", "action": best})["terminated"]
    """)
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=20, seed=0,
                           allow_hints=True)
    assert result.agreement == 1.0 and result.fouls.hints_refused == 0


def test_a_player_that_hangs_times_out_and_is_ended(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "hang.py", PLAYS_STICK + """
    import time
    ask({"cmd": "reset"})
    time.sleep(600)
    """)
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=4, seed=0,
                           decision_timeout=0.2)
    assert result.fouls.timeouts == 3 and result.episodes == 4
    assert "no decision within 0.2 s 3 times in a row" in result.status
    assert result.status.endswith("the program was ended") and result.seconds < 30


def test_a_player_that_floods_requests_that_are_not_moves_times_out(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "flood.py", PLAYS_STICK + """
    ask({"cmd": "reset"})
    while True:
        ask({"cmd": "render"})
    """)
    # A short decision time: the player and the benchmark keep a core each busy until it ends.
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=2, seed=0,
                           decision_timeout=0.1)
    assert result.fouls.timeouts == 3 and result.episodes == 2
    assert result.status.endswith("the program was ended")


def test_a_player_that_stops_reading_is_done_for(tmp_path: Path) -> None:
    cmd = _script(tmp_path, "deaf.py", PLAYS_STICK + """
    ask({"cmd": "reset"})
    while True:  # requests without ever reading an answer: the pipe back fills up
        print('{"cmd": "render"}', flush=True)
    """)
    # The pipe back must fill within the first decision's time, however loaded the machine.
    result = run_benchmark("blackjack", ProcessPlayer(cmd), episodes=2, seed=0,
                           decision_timeout=1.0)
    assert "it stopped reading its input in episode 1 of 2" in result.status
    assert result.episodes == 2 and result.fouls.defaulted == 3
    assert result.status.endswith("the program was ended")


def test_players_that_cannot_start_say_why(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(PlayerError, match="cannot start"):
        run_benchmark("blackjack", ProcessPlayer("no-such-program-here"), episodes=1, seed=0)
    code, _, err = _cli(capsys, "benchmark", "blackjack", "--agent-cmd", "no-such-program-here",
                        "--no-record")
    assert code == 2 and "cannot start 'no-such-program-here'" in err
    assert "Traceback" not in err
    code, _, err = _cli(capsys, "benchmark", "blackjack", "--agent", str(tmp_path / "none.tgym"),
                        "--no-record")
    assert code == 2 and "none.tgym" in err
    code, _, err = _cli(capsys, "benchmark", "blackjack", "--no-record")
    assert code == 2 and "name a player" in err
    code, _, err = _cli(capsys, "benchmark", "blackjack", "--agent", "optimal", "--param",
                        "size=4", "--no-record")
    assert code == 2 and "takes natural, sab, not 'size'" in err


def test_a_saved_agent_plays_its_own_game(tmp_path: Path) -> None:
    from tui_gym.session.session import Session

    session = Session(env_id="blackjack", seed=0)
    session.hp = session.hp.replace(episodes=20_000)
    session.reset_agent()
    session.train()
    path = session.save(tmp_path / "bj.tgym")
    agent = AgentPlayer(str(path), seed=0)
    result = run_benchmark("blackjack", agent, episodes=200, seed=0)
    assert result.player == "agent bj.tgym" and result.agreement > 0.6
    with pytest.raises(PlayerError, match="plays Blackjack"):
        agent.check_game("tui_gym/GridWorld-v0")
