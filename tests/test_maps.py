"""Maps: text round-trips, bad files named by row and column, edits, random maps, walls,
and the CLI seeing the same maps (`--map-file`, `tui-gym maps`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.test_cli import run
from tui_gym.cli import main
from tui_gym.games import game_for
from tui_gym.games.maps import GridMap, MapError, format_map, parse_map
from tui_gym.games.maps.builtin import BUILTIN_MAPS
from tui_gym.games.maps.files import read_map_file, write_map_file
from tui_gym.games.maps.random_map import random_map

DETOUR = "# a comment\nreward 1,2: -1.5\nslip 0,1: 0.25\nSFFG\nFHRF\n"


def optimum(game: str, grid_map: GridMap, **kwargs: object) -> float:
    g = game_for(game)
    return float(g.oracle.optimum(g.normalize_kwargs(g.with_map(kwargs, grid_map))).value)


@pytest.mark.parametrize("entry", BUILTIN_MAPS, ids=lambda m: m.name)
def test_builtin_maps_round_trip(entry, tmp_path: Path) -> None:
    path = write_map_file(tmp_path / f"{entry.name}.txt", entry.grid_map)
    assert read_map_file(path) == entry.grid_map
    assert parse_map(format_map(entry.grid_map)) == entry.grid_map


def test_header_round_trips_and_plain_rows_are_a_lake() -> None:
    grid_map = parse_map(DETOUR)
    assert grid_map.reward_table() == {(1, 2): -1.5}
    assert grid_map.slip_table() == {(0, 1): 0.25}
    assert parse_map(format_map(grid_map, "a note")) == grid_map
    lake = parse_map("SFFF\nFHFH\nFFFH\nHFFG\n")
    assert lake == next(m for m in BUILTIN_MAPS if m.name == "4x4").grid_map


@pytest.mark.parametrize(("text", "expected"), [
    ("SFFF\nFHXH\n", "line 2 (map row 1), column 2: 'X' is not a tile"),
    ("SFFF\nFHF\n", "line 2 (map row 1) has 3 tiles, row 0 has 4"),
    ("SFFF\nFSFG\n", "line 2 (map row 1), column 1: a second start"),
    ("SFRG\n", "line 1 (map row 0), column 2: a reward cell needs its value"),
    ("reward 0,1: 2\nSFFG\n", "line 2 (map row 0), column 1 is floor"),
    ("slip 0,0: 1.5\nSFFG\n", "line 1: the slip at row 0, col 0 must be in [0, 1]"),
    ("reward 5,5: 1\nSFFG\n", "row 5, col 5 is off the 1x4 map"),
    ("# nothing\n", "no rows of tiles"),
])
def test_bad_maps_say_where(text: str, expected: str) -> None:
    with pytest.raises(MapError) as error:
        parse_map(text)
    assert expected in str(error.value)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(("text", "expected"), [
    (f"reward 0,2: {'9' * 400}\nSFRG\n", "must be a finite number, got '999999999999…999999' "
     "(400 characters)"),
    (f"slip 0,0: 0.{'5' * 400}9x\nSFFG\n", "(404 characters)"),
    (f"reward {'1' * 5000},0: 1\nSFRG\n", "a header line reads"),
])
def test_long_values_in_a_map_are_quoted_short(text: str, expected: str) -> None:
    with pytest.raises(MapError) as error:
        parse_map(text)
    assert expected in str(error.value) and len(str(error.value)) < 160, str(error.value)


def test_bad_files_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.txt"
    bad.write_text("SFFF\nFHFH\nFF?H\nHFFG\n")
    code, out, err = run(capsys, "optimal", "frozenlake", "--map-file", str(bad))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "(map row 2), column 2: '?' is not a tile" in err
    with pytest.raises(MapError, match="no such file"):
        read_map_file(tmp_path / "missing.txt")
    with pytest.raises(MapError, match="not UTF-8"):
        (tmp_path / "bin.txt").write_bytes(b"\xff\xfe\x00S")
        read_map_file(tmp_path / "bin.txt")


def test_edits_and_undo_are_maps() -> None:
    grid_map = GridMap.of(["SFF", "FFG"])
    walled = grid_map.painted((0, 1), "wall")
    assert walled.cells == ("SWF", "FFG") and grid_map.cells == ("SFF", "FFG")
    assert walled.painted((0, 1), "floor") == grid_map  # undo is the map before
    pit = grid_map.painted((1, 1), "hole", -5.0)
    assert pit.reward_table() == {(1, 1): -5.0}
    iced = grid_map.painted((1, 0), "ice", 0.3)
    assert iced.cells == grid_map.cells and iced.slip_table() == {(1, 0): 0.3}
    with pytest.raises(ValueError, match="start cannot be painted over"):
        grid_map.painted((0, 0), "wall")
    assert grid_map.resized(3, 4).cells == ("SFFF", "FFGF", "FFFF")
    blocked = walled.painted((1, 1), "wall")
    assert not blocked.goal_reachable() and walled.goal_reachable()


def test_the_optimum_follows_edits() -> None:
    """CliffWalking's rules: every step costs 1, so the optimum is minus the fewest steps;
    with no way to the goal it is the whole limit of 200 steps."""
    grid_map = GridMap.of(["SFF", "FFG"])
    assert optimum("cliffwalking", grid_map) == pytest.approx(-3.0)
    around = grid_map.painted((1, 1), "wall").painted((0, 2), "wall")
    assert optimum("cliffwalking", around) == pytest.approx(-200.0)
    pit = grid_map.painted((0, 1), "hole", 5.0).painted((1, 0), "wall")
    assert optimum("cliffwalking", pit) == pytest.approx(5.0)  # falling in pays best


def test_random_maps_are_solvable_and_seeded() -> None:
    first = random_map(8, 8, 0.4, seed=3)
    assert first == random_map(8, 8, 0.4, seed=3) and first.goal_reachable()
    assert random_map(8, 8, 0.4, seed=4) != first
    walled = random_map(6, 6, 0.3, seed=1, walled=True)
    assert walled.free_connected() and walled.tiles() <= {"F", "W"}


def test_gridworld_walls_lengthen_shortest_paths() -> None:
    game = game_for("gridworld")
    pillar = parse_map("FFF\nFWF\nFFF\n")
    kwargs = game.normalize_kwargs(game.with_map({}, pillar))
    assert game.make_kwargs(kwargs)["walls"] == [[1, 1]]
    assert game.normalize_kwargs({"size": 3, "walls": [[1, 1]]}) == kwargs
    # 8 free cells on a ring: from each, the others are 1, 1, 2, 2, 3, 3, 4 steps away.
    assert game.oracle.optimum(kwargs).figures["optimal_mean_steps"] == pytest.approx(16 / 7)
    marks = game.oracle.optimal_marks(kwargs)
    perfect = game.oracle.reference(marks.astype(float), kwargs)
    assert perfect.figures["optimal_pair_fraction"] == pytest.approx(1.0)
    figures = game.oracle.agent_figures(marks.astype(float), kwargs)
    assert figures == {"steps_over_optimal": pytest.approx(0.0), "solved_fraction": 1.0}
    assert np.shape(marks) == (81, 4)


def test_cli_sees_the_same_maps(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "maps", "--json")
    assert code == 0, err
    names = [m["name"] for m in json.loads(out)["maps"]]
    assert {"4x4", "8x8", "cliff", "maze"} <= set(names)
    code, text, err = run(capsys, "maps", "4x4")
    assert code == 0 and text == "SFFF\nFHFH\nFFFH\nHFFG\n"
    path = tmp_path / "lake.txt"
    path.write_text(text)
    from_file = json.loads(run(capsys, "optimal", "frozenlake", "--map-file", str(path),
                               "--json")[1])
    builtin = json.loads(run(capsys, "optimal", "frozenlake", "--json")[1])
    assert from_file["optimal_value"] == pytest.approx(builtin["optimal_value"], abs=1e-9)
    code, out, err = run(capsys, "maps", "--random", "5x5", "--map-seed", "2", "--json")
    assert code == 0 and json.loads(out)["goal_reachable"]
    code, out, err = run(capsys, "optimal", "blackjack", "--map-file", str(path))
    assert code == 2 and "--map-file applies to" in err


def test_the_edit_to_optimum_figure_exists() -> None:
    from tui_gym.bench.map_edit import measure
    from tui_gym.bench.report import verdicts
    from tui_gym.bench.run import BenchResults, MachineInfo

    results = measure(edits=4)
    assert {r.game for r in results} == {"FrozenLake", "CliffWalking"}
    for result in results:
        assert result.size == "12x12" and result.edits == 4 and result.kept_agent
        assert 0 < result.median_ms <= result.worst_ms
    found = BenchResults(quick=True, seconds=1.0, machine=MachineInfo(2, None, None),
                         map_edit=tuple(results))
    assert set(verdicts(found)) >= {"map_edit_ms[FrozenLake]", "map_edit_ms[CliffWalking]"}


def test_the_walled_gridworld_model_moves_round_walls_as_the_env_does() -> None:
    from tui_gym.core.obskey import ObservationKeyer
    from tui_gym.core.wrappers.changes import NO_CHANGES
    from tui_gym.envs.gridworld import GridWorldEnv
    from tui_gym.games.gridworld.paths import gridworld_model

    walls = ((2, 1), (2, 2), (1, 3))
    model = gridworld_model(5, 1.0, 0.0, NO_CHANGES, walls)
    env = GridWorldEnv(size=5, walls=walls)
    keyer = ObservationKeyer(env.observation_space)
    starts = np.flatnonzero(model.initial)
    placements = [keyer.decode(int(s)) for s in starts]
    assert not any(p[:2] in walls or p[2:] in walls for p in placements)
    rng = np.random.default_rng(0)
    for state in rng.choice(starts, size=60):
        ax, ay, tx, ty = keyer.decode(int(state))
        action = int(rng.integers(4))
        env.reset(options={"agent": (ax, ay), "target": (tx, ty)})
        obs, reward, terminated, _, _ = env.step(action)
        assert model.outcomes(int(state), action) == [
            (1.0, keyer.key(obs), reward, terminated)]


def test_train_and_play_on_a_map_file(tmp_path: Path, capsys, monkeypatch) -> None:
    import io
    import sys

    path = tmp_path / "corridor.txt"
    path.write_text("reward 0,2: 2\nSFRFG\n")
    code, out, err = run(capsys, "train", "cliffwalking", "--map-file", str(path),
                         "--episodes", "50", "--eval-episodes", "10", "--json")
    assert code == 0, err
    assert json.loads(out)["env_kwargs"]["layout"] == "reward 0,2: 2\nSFRFG\n"
    lines = ['{"cmd": "reset", "seed": 1}', json.dumps({"cmd": "step", "action": "right"}),
             json.dumps({"cmd": "step", "action": "right"})]
    stdin = io.TextIOWrapper(io.BytesIO("".join(f"{line}\n" for line in lines).encode()))
    monkeypatch.setattr(sys, "stdin", stdin)
    assert main(["play", "cliffwalking", "--map-file", str(path), "--jsonl"]) == 0
    answers = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [a.get("observation") for a in answers] == [0, 1, 2]
    assert answers[2]["reward"] == 2.0


def _outcomes(table, s: int, a: int) -> dict:
    out: dict = {}
    for p, nxt, reward, done in table[s][a]:
        key = (int(nxt), float(reward), bool(done))
        out[key] = out.get(key, 0.0) + float(p)
    return {k: round(v, 12) for k, v in out.items() if v > 0}


@pytest.mark.parametrize("name", ["frozenlake", "cliffwalking"])
@pytest.mark.parametrize("slippery", [False, True])
def test_gymnasium_maps_move_the_same_on_the_tile_map_env(name: str, slippery: bool) -> None:
    """The TileMap env on Gymnasium's own map and rules has Gymnasium's transitions."""
    import gymnasium as gym

    game = game_for(name)
    kwargs = game.normalize_kwargs({"slippery": slippery})
    own = gym.make(game.env_id, **game.make_kwargs(kwargs)).unwrapped
    edited = game.normalize_kwargs(game.with_map(kwargs, game.grid_map(kwargs)))
    tiles = gym.make("tui_gym/TileMap-v0", **{
        k: v for k, v in game.make_kwargs(edited).items() if k != "max_episode_steps"
    }).unwrapped
    standing = [i for i, tile in enumerate("".join(game.cells(kwargs))) if tile in "SF"]
    for s in standing:  # where an agent can stand: the cliff and the ends never act
        for a in range(4):
            assert _outcomes(tiles.P, s, a) == _outcomes(own.P, s, a), (s, a)


@pytest.mark.parametrize(("flag", "text"), [("--map-seed", "١٢"), ("--density", "٠.٢")])
def test_random_map_numbers_take_digits_0_to_9_only(capsys, flag: str, text: str) -> None:
    code, out, err = run(capsys, "maps", "--random", "4x4", flag, text)
    assert code == 2 and not out
    assert f"argument {flag}:" in err and f"got {text!r} (digits 0-9 only)" in err
