"""The side panel's wrapper chain names the env that is built, an edited map's included."""

from __future__ import annotations

from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.session import Session
from tui_gym.ui.side_panel import chain_text


def test_the_chain_names_the_game_its_wrappers_and_gymnasiums_repr() -> None:
    session = Session("frozenlake", seed=0,
                      choices=(WrapperChoice("TimeLimit", (("max_episode_steps", 40),)),))
    lines = chain_text(session).plain.splitlines()
    assert lines[0] == "FrozenLake-v1"
    assert lines[1:3] == ["1 TimeLimit", "    max_episode_steps=40"]
    assert lines[3].startswith("<TimeLimit<") and "FrozenLake-v1" in lines[3]


def test_an_edited_map_names_the_env_it_plays_on() -> None:
    session = Session("frozenlake", env_kwargs={"layout": "SF\nHG\n"}, seed=0)
    lines = chain_text(session).plain.splitlines()
    assert lines[0] == ("tui_gym/TileMap-v0  (FrozenLake-v1's rules on the edited map)"
                        "  (no wrappers)")
    assert "TileMap-v0" in lines[1] and "FrozenLake" not in lines[1]
