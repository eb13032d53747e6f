"""The contract every game in `GAMES` keeps, checked over the registry.

Every game builds, keys its base states, round-trips through a save file,
plays one episode through the CLI and the JSON-lines protocol, is switched to
and played by key in the app (one game of each kind of board to the episode's end), and
with its default hyperparameters trains to the bound its oracle states.
Where a game has an exact value, the sampled returns of a fixed policy on the
real env and on the model the engine trains on agree with it within a bound
computed from the sample (four standard errors); a model read from a transition table
agrees with the env's every move. Sample sizes are small: a bound from the
sample size is as strict as the sample allows, and the suite stays fast.
"""

from __future__ import annotations

import io
import json
import math
import sys
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from textual.binding import Binding

from tests.mdp_support import sampled_returns
from tests.test_contract_learners import GAMES as LEARNER_GAMES
from tests.waiting import send_key, settle, wait_busy
from tui_gym.cli import main
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.wrappers import parse_wrapper_spec
from tui_gym.games import GAMES, Game, game_for
from tui_gym.games.model import ModelGame
from tui_gym.session.protocol import JsonlPlayer
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp

Z = 4.0  # standard errors a sampled mean may stray from the exact value
IDS = [game.name for game in GAMES]
# Model games in the arguments worth checking apart (slippery, larger, random maps).
VARIANTS = [
    ("frozenlake", {}),
    ("frozenlake", {"map": "8x8"}),
    ("frozenlake", {"slippery": False}),
    ("frozenlake", {"map": "random", "size": 5, "map_seed": 3, "success_rate": 0.6}),
    ("cliffwalking", {}),
    ("cliffwalking", {"slippery": True}),
    ("taxi", {}),
    ("taxi", {"rainy": True}),
    ("ab-grid", {}),
    ("corner-grid", {}),
    ("gambler", {}),
    ("gambler", {"p_heads": 0.55, "goal": 30}),
    ("random-walk", {}),
    ("random-walk", {"states": 19}),
    ("windy", {}),
    ("windy", {"stochastic_wind": True}),
    ("windy-king", {"stochastic_wind": True}),
    ("dyna-maze", {}),
    ("dyna-maze", {"scale": 2}),
    # The changing mazes' first phase for as long as these tests play (the second phase
    # against the env: tests/test_book_worlds.py).
    ("blocking-maze", {"change_at": 100_000_000}),
    ("shortcut-maze", {"change_at": 100_000_000}),
    ("max-bias", {}),
]
VARIANT_IDS = [f"{name}-{'-'.join(f'{k}={v}' for k, v in kw.items()) or 'default'}"
               for name, kw in VARIANTS]


def _session(name: str, kwargs: dict[str, Any] | None = None, **extra: Any) -> Session:
    return Session(name, env_kwargs=kwargs or {}, seed=0, **extra)


def _optimal_q(session: Session) -> np.ndarray:
    optimum = session.game.oracle.optimum(session.env_kwargs)
    assert not isinstance(optimum, NotAvailable) and optimum.q is not None
    q = np.asarray(optimum.q, dtype=float)
    if optimum.marks is not None:  # of the optimal moves, a quickest (a maze's: all worth +1)
        q = q + np.asarray(optimum.marks, dtype=float)
    return np.where(np.isfinite(q), q, -1e9)


def _within(samples: np.ndarray, exact: float) -> None:
    error = Z * samples.std(ddof=1) / math.sqrt(len(samples)) + 1e-9
    assert abs(samples.mean() - exact) <= error, (samples.mean(), exact, error)


# --- every game ----------------------------------------------------------------


@pytest.mark.parametrize("game", GAMES, ids=IDS)
def test_builds_with_its_arguments_and_reads_its_states(game: Game) -> None:
    session = _session(game.name)
    assert game.matches(session.env_id) and session.game is game
    assert set(session.env_kwargs) == {p.name for p in game.params}
    assert session.agent.n_actions == len(game.action_names)
    assert game.key and game.description and game.teaches
    env = session.make_env(render_mode=game.render_mode)
    obs, _ = env.reset(seed=0)
    assert game.states.scene(env) and game.states.describe(obs, session.env_kwargs)
    assert game.oracle.advice(env, session.env_kwargs).note
    env.close()
    # A state of another shape reads as text, never as an exception.
    assert game.states.describe(object(), session.env_kwargs)


@pytest.mark.parametrize("game", GAMES, ids=IDS)
def test_base_states_have_keys_and_heatmaps(game: Game) -> None:
    session = _session(game.name)
    keys = session.base_keys()
    assert keys is not None and len(set(keys)) == len(keys)
    assert all(0 <= key < session.keyer.n_states for key in keys)
    panels = session.heatmaps()
    assert panels and all(p.values.shape == p.marked.shape for p in panels)
    assert session.reference() is not None


@pytest.mark.parametrize("game", GAMES, ids=IDS)
def test_save_and_load_round_trip(game: Game, tmp_path) -> None:
    session = _session(game.name, engine="env")
    session.trainer.run(episodes=15)
    loaded = Session.load(session.save(tmp_path / "agent.tgym"))
    assert (loaded.env_id, loaded.env_kwargs) == (session.env_id, session.env_kwargs)
    assert np.array_equal(loaded.agent.table()[0], session.agent.table()[0])
    assert loaded.trainer.episodes == 15


# The default learner's training on the games tests/test_contract_learners.py trains
# every learner on is checked there, against the same bound.
UNLEARNED = [game for game in GAMES if game.name not in LEARNER_GAMES]


@pytest.mark.parametrize("game", UNLEARNED, ids=[game.name for game in UNLEARNED])
def test_default_training_reaches_the_stated_bound(game: Game) -> None:
    session = _session(game.name)
    bound = game.oracle.bound(session.env_kwargs, session.changes)
    assert not isinstance(bound, NotAvailable)
    session.train()
    reference = session.reference()
    assert reference is not None and bound.met(reference.figures), (bound, reference.figures)


@pytest.mark.parametrize("game", GAMES, ids=IDS)
def test_the_cli_trains_and_plays(game: Game, capsys, monkeypatch) -> None:
    code = main(["train", game.name, "--episodes", "3", "--engine", "env",
                 "--eval-episodes", "2", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["episodes"] == 3
    lines = ['{"cmd": "reset", "seed": 1}', '{"cmd": "hint"}', '{"cmd": "render"}',
             json.dumps({"cmd": "step", "action": game.action_names[0]})]
    stdin = io.TextIOWrapper(io.BytesIO("".join(f"{line}\n" for line in lines).encode()))
    monkeypatch.setattr(sys, "stdin", stdin)
    assert main(["play", game.name, "--jsonl"]) == 0
    answers = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert len(answers) == 4 and not any("error" in a for a in answers), answers
    assert answers[3]["info"] is not None


@pytest.mark.parametrize("game", GAMES, ids=IDS)
def test_a_program_plays_one_episode_by_the_hints(game: Game) -> None:
    player = JsonlPlayer(_session(game.name), seed=3)
    answer = player.handle('{"cmd": "reset"}')
    for _ in range(400):
        hint = player.handle('{"cmd": "hint"}')
        action = (hint.get("optimal_actions") or [game.action_names[0]])[0]
        answer = player.handle(json.dumps({"cmd": "step", "action": action}))
        assert "error" not in answer, answer
        if answer["terminated"] or answer["truncated"]:
            break
    assert answer["terminated"] or answer["truncated"]


def _keys_for(board: Any, action: str) -> list[str]:
    """The keys that make a move: its own, or those a board says pick it (a dial's)."""
    if hasattr(board, "keys_for"):
        return list(board.keys_for(action))
    for binding in Binding.make_bindings(board.BINDINGS):
        if binding.action == f"act('{action}')":
            return [binding.key]
    raise AssertionError(f"no key for {action}")


# One game of each kind of board plays a whole episode in the app (the boards and the
# play view are the same code for every game of a kind; each game's own keys on its board
# are checked on the board alone, tests/test_ui_board_*.py). Frozen Lake's optimum takes
# more than 15 moves from the first start: a time limit ends it.
WHOLE_EPISODES = ("blackjack", "gridworld", "frozenlake", "taxi", "gambler")
LONG_EPISODES = ("frozenlake",)


def test_the_whole_episodes_cover_every_kind_of_board() -> None:
    kinds = {game.board for game in GAMES}
    assert {game_for(name).board for name in WHOLE_EPISODES} == kinds


async def _play(pilot: Any, game: Game, moves: int) -> None:
    """Press the key of the optimal move (the first move where none is) up to `moves`
    times or until the episode ends, each press checked to make one move."""
    app = pilot.app
    view = app.play_view
    # Each key is handled in full before the next; the frames in between, which nothing
    # here reads, are drawn once at the end.
    with app.batch_update():
        for _ in range(moves):
            human = view.game
            assert human is not None and view.board is not None
            if human.done:
                break
            advice = game.oracle.advice(human.env, app.session.env_kwargs)
            action = game.action_names[advice.optimal[0] if advice.optimal else 0]
            steps = human.last.steps if human.last else 0
            for key in _keys_for(view.board, action):
                send_key(pilot, key)
                await settle(pilot)
            assert human.last is not None and (
                human.last.steps == steps + 1 or human.done
            ), game.name
    await settle(pilot)


async def test_a_person_switches_to_every_game_by_its_key_and_plays_in_the_app() -> None:
    # One app that starts on the first game switches to each game in turn by the game's
    # own key, as a person would, and makes a move on its board by key; one game of each
    # kind of board is played to the end of an episode. A time limit keeps the episode
    # short where the optimum takes its time.
    limit = parse_wrapper_spec("TimeLimit:max_episode_steps=15")
    app = TuiGymApp(_session(GAMES[0].name))
    async with app.run_test(size=(80, 24)) as pilot:
        await settle(pilot)
        view = app.play_view
        for game in GAMES:
            if app.session.game is not game:
                send_key(pilot, game.key)  # built off the event loop
                await wait_busy(pilot, lambda g=game: app.session.game is g, game.name)
            whole = game.name in WHOLE_EPISODES
            if game.name in LONG_EPISODES:
                assert app.rebuild(choices=(limit,)), game.name
            await settle(pilot)
            assert app.focused is view.board, f"{game.name}: the board has the keyboard"
            assert view.game is not None and view.game.game is game
            await _play(pilot, game, 200 if whole else 1)
            assert view.game.last is not None, game.name
            if whole:
                assert view.game.done, game.name
            assert str(view.query_one("#play-headline").render()), game.name


# --- exact values against play ---------------------------------------------------


def _play_env(session: Session, q: np.ndarray, episodes: int) -> np.ndarray:
    """Returns of `episodes` episodes of the real env, greedy on `q` (rows: base states)."""
    keys = session.base_keys()
    assert keys is not None
    greedy = dict(zip(keys, np.argmax(q, axis=1).tolist(), strict=True))
    key = session.keyer.key
    env = session.make_env()
    returns = np.zeros(episodes)
    obs, _ = env.reset(seed=11)
    for i in range(episodes):
        if i:
            obs, _ = env.reset()
        done = False
        while not done:
            action = greedy.get(key(obs), 0)
            obs, reward, terminated, truncated, _ = env.step(action)
            returns[i] += float(reward)
            done = terminated or truncated
    env.close()
    return returns


def _play_model(session: Session, q: np.ndarray, episodes: int) -> np.ndarray:
    """The same policy played on the model the engine trains on, `episodes` at once."""
    training = session.training
    assert training is not None, session.engine_reason
    model = training.model
    rows = np.arange(model.n_states) if training.rows is None else training.rows
    keys = session.base_keys()
    assert keys is not None
    base_of = np.full(session.keyer.n_states, -1)
    base_of[np.asarray(keys)] = np.arange(len(keys))
    bases = base_of[rows]
    policy = np.where(bases >= 0, np.argmax(q[np.maximum(bases, 0)], axis=1), 0)
    return sampled_returns(model, policy, episodes, np.random.default_rng(5), max_steps=1000)


def _exact_value(session: Session, q: np.ndarray) -> float | None:
    one_hot = np.zeros_like(q)
    one_hot[np.arange(len(q)), np.argmax(q, axis=1)] = 1.0
    reference = session.game.oracle.reference(one_hot, session.env_kwargs, session.changes)
    assert not isinstance(reference, NotAvailable)
    return reference.figures.get("exact_value")


@pytest.mark.parametrize(("name", "kwargs"), [("blackjack", {}), ("car-rental", {}), *VARIANTS],
                         ids=["blackjack", "car-rental", *VARIANT_IDS])
def test_sampled_returns_of_a_fixed_policy_agree_with_its_exact_value(
    name: str, kwargs: dict
) -> None:
    session = _session(name, kwargs)
    q = _optimal_q(session)
    exact = _exact_value(session, q)
    assert exact is not None
    _within(_play_env(session, q, 300), exact)
    # The compiled loop plays one model (drawing the noise of rewards that have it): not a
    # world that changes.
    if session.training is not None:
        _within(_play_model(session, q, 4000), exact)


def test_the_grid_model_agrees_with_the_env() -> None:
    session = _session("gridworld")
    q = _optimal_q_grid(session)
    played, model = _play_env(session, q, 200), _play_model(session, q, 4000)
    # The shortest-path policy reaches the target from every placement: both pay 1.
    assert played.min() == played.max() == model.min() == model.max() == 1.0


def _optimal_q_grid(session: Session) -> np.ndarray:
    marks = session.game.oracle.optimal_marks(session.env_kwargs)
    assert not isinstance(marks, NotAvailable)
    return np.asarray(marks, dtype=float)


@pytest.mark.parametrize(("name", "kwargs"), VARIANTS, ids=VARIANT_IDS)
def test_the_model_agrees_with_every_move_of_the_env(name: str, kwargs: dict) -> None:
    game = game_for(name)
    assert isinstance(game, ModelGame)
    normal = game.normalize_kwargs(kwargs)
    model = game.base_model(normal)
    assert not isinstance(model, NotAvailable)
    env = gym.make(game.env_id, **game.make_kwargs(normal)).unwrapped
    env.reset(seed=0)
    noisy = np.zeros(model.prob.shape[:2], bool) if model.reward_std is None else (
        model.reward_std.any(axis=2))
    for s in range(model.n_states):
        for a in range(model.n_actions):
            outcomes = {(n, r, t): p for p, n, r, t in model.outcomes(s, a)}
            # A certain move is checked once, a random one by a few draws of the env; a
            # reward drawn with noise is the model's mean only on average (checked apart).
            for _ in range(1 if len(outcomes) == 1 and not noisy[s, a] else 6):
                env.s = s
                nxt, reward, terminated, _, _ = env.step(a)
                seen = (int(nxt), float(reward), bool(terminated))
                if noisy[s, a]:
                    assert seen[::2] in {(n, t) for n, _, t in outcomes}, (s, a)
                else:
                    assert seen in outcomes, (s, a)
    env.close()
    assert abs(model.initial.sum() - 1) < 1e-9
    assert np.allclose(model.initial, np.asarray(env.initial_state_distrib))


def test_exact_values_of_the_games_are_the_known_ones() -> None:
    known = {
        ("frozenlake", ()): 0.744190,
        ("frozenlake", (("slippery", False),)): 1.0,
        ("frozenlake", (("map", "8x8"),)): 0.913220,
        ("cliffwalking", ()): -13.0,
        ("taxi", ()): 7.93,
    }
    for (name, kwargs), value in known.items():
        game = game_for(name)
        optimum = game.oracle.optimum(game.normalize_kwargs(dict(kwargs)))
        assert not isinstance(optimum, NotAvailable)
        assert optimum.value == pytest.approx(value, abs=5e-7)
