"""Counts agree with their nouns wherever the games speak."""

from __future__ import annotations

from tui_gym.games.words import plural
from tui_gym.session.session import Session


def test_plural_agrees_and_groups_thousands() -> None:
    assert plural(1, "step") == "1 step"
    assert plural(0, "hand") == "0 hands"
    assert plural(1_200, "episode") == "1,200 episodes"


def test_the_gridworld_coach_says_one_step_to_go() -> None:
    session = Session("gridworld", seed=3)
    env, game = session.env, session.game
    env.reset(seed=3)
    while True:
        advice = game.oracle.advice(env, session.env_kwargs)
        if "(1 step to go)" in advice.note:
            break
        assert "steps to go" in advice.note, advice.note
        env.step(advice.optimal[0])
