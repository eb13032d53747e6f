"""The arena: seats judged by the exact optimum of the game as its wrappers make it, scores
in constant memory, and a table of games that is bounded and forgets idle ones."""

from __future__ import annotations

import math

import pytest

from tui_gym.session.arena import (
    ArenaScore,
    GameTable,
    Seat,
    SeatError,
    Verdict,
    catalog,
    find_game,
    open_handler,
)


def _seat(game: str, seed: int, wrappers: tuple[str, ...] = ()) -> Seat:
    entry = find_game(game)
    return Seat(open_handler(entry.env_id, None, seed, wrappers), entry, seed)


def test_the_catalog_lists_every_game_with_its_actions() -> None:
    names = [entry.name for entry in catalog()]
    assert "blackjack" in names and "gridworld" in names
    for entry in catalog():
        assert entry.actions and find_game(entry.env_id) == entry
    with pytest.raises(ValueError, match="'chess'"):
        find_game("chess")


def test_a_costly_move_costs_its_exact_regret_in_the_wrapped_game() -> None:
    plain = _seat("blackjack", 7)
    doubled = _seat("blackjack", 7, ("ScaleReward:factor=2",))
    try:
        for seat in (plain, doubled):
            seat.reset()
        _, verdict = plain.step("hit")
        _, scaled = doubled.step("hit")
        assert verdict.decision and verdict.agreed is False and verdict.regret > 0.5
        assert scaled.regret == pytest.approx(2 * verdict.regret)  # regret in wrapped rewards
    finally:
        plain.close()
        doubled.close()


def test_a_wrapper_beyond_the_exact_figures_leaves_moves_unjudged() -> None:
    seat = _seat("blackjack", 7, ("StickyAction:repeat_action_probability=0.5",))
    try:
        seat.reset()
        _, verdict = seat.step("stick")
        assert not verdict.decision and "beyond its exact figures" in verdict.note
        score = seat.score.to_json()
        assert score["decisions"] == 0 and score["regret"]["mean_per_episode"] is None
        assert score["regret"]["note"] == "regret unavailable: 1 move could not be judged: " \
            "the wrappers change the game beyond its exact figures"
    finally:
        seat.close()


def test_moves_are_checked_before_they_are_made() -> None:
    seat = _seat("gridworld", 3)
    try:
        with pytest.raises(SeatError, match="no episode running"):
            seat.step("up")
        seat.reset()
        with pytest.raises(SeatError, match="valid actions: 0=right, 1=up, 2=left, 3=down"):
            seat.step("jump")
        assert seat.action_name(1) == seat.action_name("UP") == seat.action_name("1") == "up"
        assert seat.observe()["legal_actions"] == ["right", "up", "left", "down"]
    finally:
        seat.close()


def test_the_score_counts_finished_episodes_and_keeps_the_running_one_apart() -> None:
    score = ArenaScore()
    score.start_episode(1)
    score.record(Verdict(True, False, 0.25, ("stick",)), 0.0, False, False)
    score.record(Verdict(True, True, 0.0, ("stick",)), -1.0, True, True)
    score.start_episode(2)
    score.record(Verdict(True, True, None, ("hit",), None, "no values"), 0.0, False, False)
    data = score.to_json()
    assert (data["episodes"], data["decisions"], data["agreed"]) == (1, 2, 1)
    assert data["regret"]["mean_per_episode"] == 0.25 and data["mean_return"] == -1.0
    assert data["current_episode"]["regret"] is None  # one decision had no values
    assert "current_episode" not in score.to_json(running=False)
    score.record(Verdict(False), 1.0, True, True)
    assert score.to_json()["regret"]["note"] == "regret unavailable for 1 of 3 decisions: " \
                                                "no values"
    assert not any(isinstance(v, float) and not math.isfinite(v)
                   for v in score.to_json()["regret"].values() if v is not None)


def test_the_table_is_bounded_and_forgets_idle_games() -> None:
    now = [100.0]
    table = GameTable(max_games=2, idle_timeout=10, clock=lambda: now[0])
    try:
        first, _ = table.start("blackjack", seed=1)
        second, _ = table.start("gridworld", {"size": 3}, seed=1)
        with pytest.raises(ValueError, match="2 games are running"):
            table.start("blackjack")
        now[0] = 109.0
        table.get(first)  # used: stays
        now[0] = 111.0  # the second has been idle for 11 s
        assert table.expire() == [second] and table.ids() == [first]
        with pytest.raises(ValueError, match=f"game {second} expired after 10 s"):
            table.get(second)
        with pytest.raises(ValueError, match="no game 99"):
            table.get(99)
        with pytest.raises(ValueError, match="size is out of range"):
            table.start("gridworld", {"size": 1000})
        assert len(table) == 1
    finally:
        table.close()
    with pytest.raises(ValueError):
        GameTable(max_games=0)
