"""Bring your own env: an env of the tests' own, played through the CLI, protocol and app.

`tests.tiny_env:TinyChain-v0` is Gymnasium's `module:id` form: the module
registers the env when imported. No code of tui-gym names it; the generic
game reads its table. An env that does not fit says in one line what it lacks.
"""

from __future__ import annotations

import io
import json
import sys

import numpy as np
import pytest

from tui_gym.cli import main
from tui_gym.core.mdp import NotAvailable
from tui_gym.games import UnknownGameError, game_for, resolve_env_id
from tui_gym.games.generic import GenericGame
from tui_gym.session.protocol import JsonlPlayer
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.widgets.text_board import TextBoard

from .waiting import figures_shown, open_train

TINY = "tests.tiny_env:TinyChain-v0"


def test_the_env_is_a_generic_game_with_an_exact_optimum() -> None:
    assert resolve_env_id(TINY) == TINY
    game = game_for(TINY)
    assert isinstance(game, GenericGame) and game.action_names == ("0", "1")
    optimum = game.oracle.optimum({})
    assert not isinstance(optimum, NotAvailable)
    # Right is optimal everywhere: from the middle, a walk that moves right with chance 0.8
    # reaches the right end before the left one with chance 1 / (1 + (0.2 / 0.8) ** 2).
    assert optimum.value == pytest.approx(2 / (1 + 0.25**2) - 1, abs=1e-3)
    session = Session(TINY, seed=0)
    session.train()
    reference = session.reference()
    assert reference is not None and reference.figures["gap"] < 0.01
    assert session.trainer.engine == "model"
    panels = session.heatmaps()
    assert panels and panels[0].shape == (5, 2)


def test_the_cli_trains_and_a_program_plays(capsys, monkeypatch) -> None:
    assert main(["train", TINY, "--episodes", "2000", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["env_id"] == TINY and data["eval"]["gap"] < 0.05
    assert main(["optimal", TINY, "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)["policy"]) == 5
    lines = ['{"cmd": "reset"}', '{"cmd": "render"}', '{"cmd": "hint"}',
             '{"cmd": "step", "action": "1"}']
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO("\n".join(lines).encode())))
    assert main(["play", TINY, "--jsonl"]) == 0
    answers = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert answers[1]["text"].strip() == "..@.." and answers[2]["optimal_actions"] == ["1"]
    assert not any("error" in a for a in answers)


def test_the_protocol_plays_an_episode() -> None:
    player = JsonlPlayer(Session(TINY), seed=2)
    answer = player.handle('{"cmd": "reset"}')
    while not (answer["terminated"] or answer["truncated"]):
        answer = player.handle('{"cmd": "step", "action": 1}')
    assert answer["reward"] in (1.0, -1.0)


async def test_the_app_draws_its_text_and_plays_by_digits() -> None:
    app = TuiGymApp(Session(TINY, seed=1))
    async with app.run_test(size=(100, 30)) as pilot:
        await pilot.pause()
        board = app.play_view.board
        assert isinstance(board, TextBoard)
        assert "..@.." in str(board.canvas.render())
        for _ in range(40):
            if app.play_view.game.done:
                break
            await pilot.press("1")
        assert app.play_view.game.done
        await figures_shown(pilot, await open_train(pilot))
        assert np.asarray(app.train_view.heatmap.panels[0].values).shape == (5, 2)


@pytest.mark.parametrize(
    ("env_id", "words"),
    [
        ("CartPole-v1", "CartPole-v1 does not fit: its observation space is Box"),
        ("Blackjack-v2", "unknown environment 'Blackjack-v2'"),
        ("no_such_module:Thing-v0", "cannot import 'no_such_module'"),
    ],
)
def test_an_env_that_does_not_fit_says_what_it_lacks(env_id: str, words: str, capsys) -> None:
    with pytest.raises(UnknownGameError, match=words.replace("(", r"\(")):
        resolve_env_id(env_id)
    assert main(["train", env_id]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err
