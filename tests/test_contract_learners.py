"""The learner contract, over ALGORITHMS x games: each learns each game, both loops agree,
and every algorithm's state survives a save and a load.

- Learning: the game's defaults for the algorithm, on the game's model, seed 0,
  meet the bound the game states (`Oracle.bound`), but where the game names a
  lesson: then they end within how far short the lesson keeps them. The share
  of seeds at the bound is the bench's (`tui-gym bench`, defaults).
- Loops: the compiled loop on the model and the Python loop on the env differ
  in their random draws, so they are compared in distribution: the
  exact value the greedy policy reaches after the same number of episodes,
  averaged over seeds, agrees within a few standard errors, far from where an
  untrained (random) policy stands.
- Saving: a trained learner of each algorithm, dense and sparse, loads back
  array for array (Double Q's second table, Dyna-Q's model included), with its
  hyperparameters, episode count and the row of each key; a version 1 file
  loads as Q-learning.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tui_gym.algorithms import ALGORITHMS, Predictor
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.session import Session

NAMES = [cls.name for cls in ALGORITHMS]
# Control learners are held to the games' bounds; prediction learners score a fixed policy
# instead (tests/test_prediction.py).
CONTROL = [cls.name for cls in ALGORITHMS if not issubclass(cls, Predictor)]

GAMES = ("blackjack", "gridworld", "frozenlake", "cliffwalking", "taxi", "ab-grid",
         "corner-grid", "gambler", "car-rental", "random-walk", "windy", "windy-king",
         "dyna-maze", "max-bias")
# The env loop trains one pair to its bound too: the book's learner on the rewards drawn
# with noise (the env's draws: test_book_worlds.py; the compiled loop's: test_book_runs.py).
ENV_LOOP = (("q-learning", "max-bias"),)

# The pairs a game names a lesson for (its defaults end short of its bound by the
# learner's nature) and how far short they end, over the seeds measured (the README's
# defaults table): CliffWalking's on-policy learners take the safe path two rows up
# (-17 against -13), as in Sutton & Barto's Example 6.6.
LESSONS: dict[tuple[str, str], float | None] = {
    ("cliffwalking", "sarsa"): 4.0,
    ("cliffwalking", "expected-sarsa"): 4.0,
    ("cliffwalking", "monte-carlo"): 4.0,
    ("cliffwalking", "n-step-sarsa"): 6.0,
    ("cliffwalking", "sarsa-lambda"): 4.0,
    ("frozenlake", "dyna-q"): 0.3,
    # Prioritized sweeping's queue favours the surprising draws of a random outcome.
    ("frozenlake", "prioritized-sweeping"): 0.75,
    ("blackjack", "prioritized-sweeping"): 0.1,
    ("taxi", "monte-carlo"): 0.25,
    # Monte Carlo's greedy policy may never cross the wind (the book: "termination is not
    # guaranteed for all policies"): no figure to hold it to.
    ("windy", "monte-carlo"): None,
    ("windy", "double-q"): 2.0,
    ("windy-king", "monte-carlo"): None,
    ("windy-king", "double-q"): 6.0,
    # Every way to the goal is worth +1: SARSA may keep a detour of 2.
    ("dyna-maze", "sarsa"): 2.0,
}

PAIRS = [(name, game, "model") for name in CONTROL for game in GAMES]
PAIRS += [(name, game, "env") for name, game in ENV_LOOP]


@pytest.mark.parametrize(("name", "game", "engine"), PAIRS)
def test_each_algorithm_meets_the_games_bound_with_its_defaults(
    name: str, game: str, engine: str
) -> None:
    session = Session(game, seed=0, algorithm=name, engine=engine)
    assert session.trainer.engine == engine
    session.train()
    assert session.trainer.episodes == session.hp.episodes
    bound = session.game.oracle.bound(session.env_kwargs, session.changes)
    figures = session.reference().figures
    assert (name in session.game.lessons) == ((game, name) in LESSONS)
    if (game, name) in LESSONS:
        short = LESSONS[game, name]
        assert short is None or figures[bound.figure] <= short
    else:
        assert bound.met(figures), (bound.text, figures[bound.figure])


# Prioritized sweeping's sweeps follow the rows a transition leads into, and Blackjack's
# model ends a bust in the hand's own row where the env ends it in a bust observation's
# row: its learning speed differs between the loops (the compiled and the plain rule agree
# exactly: tests/test_algorithms_control.py).
@pytest.mark.parametrize("name", [n for n in CONTROL if n != "prioritized-sweeping"])
def test_the_model_and_env_loops_agree_in_distribution(name: str) -> None:
    values: dict[str, list[float]] = {"env": [], "model": []}
    for engine in values:
        for seed in range(3):
            session = Session("blackjack", seed=seed, algorithm=name, engine=engine,
                              hp={"episodes": 800})
            session.trainer.run(episodes=800)
            values[engine].append(session.reference().figures["exact_value"])
    env, model = np.mean(values["env"]), np.mean(values["model"])
    assert abs(env - model) < 0.05, values
    assert min(env, model) > -0.25  # both learned: random play is worth about -0.4


def _arrays(session: Session) -> tuple[dict[str, np.ndarray], list | None, dict]:
    state = session.agent.state()
    return state.arrays, state.keys, state.meta


@pytest.mark.parametrize(
    ("game", "choices", "engine"),
    [("blackjack", (), "model"),
     ("gridworld", (WrapperChoice("TimeAwareObservation", {"normalize_time": True}),),
      "env")],
    ids=["dense", "sparse"],
)
@pytest.mark.parametrize("name", NAMES)
def test_every_algorithm_saves_and_loads_its_whole_state(
    name: str, game: str, choices: tuple, engine: str, tmp_path: Path
) -> None:
    session = Session(game, {"size": 3} if game == "gridworld" else {}, choices, seed=2,
                      algorithm=name, engine=engine, hp={"episodes": 5_000, "discount": 0.9})
    session.trainer.run(episodes=40)
    assert session.agent.dense or session.agent.rows_used > 256  # grown past its first rows
    loaded = Session.load(session.save(tmp_path / "agent.tgym"))
    assert loaded.algorithm == name and type(loaded.agent) is type(session.agent)
    arrays, keys, meta = _arrays(session)
    back, back_keys, back_meta = _arrays(loaded)
    assert set(back) == set(arrays)
    for key, array in arrays.items():
        assert np.array_equal(back[key], array), key
    assert back_keys == keys
    assert back_meta == meta and loaded.hp == session.hp
    assert loaded.agent.epsilon == session.agent.epsilon
    if name == "double-q":
        assert arrays["q_b"].any() and not np.array_equal(arrays["q_a"], arrays["q_b"])
    if name in ("dyna-q", "dyna-q-plus", "prioritized-sweeping"):
        assert (arrays["model_next"] >= 0).any()
    if name in ("dyna-q", "dyna-q-plus"):
        assert len(arrays["model_tried"]) > 0


def test_a_version_1_file_loads_as_q_learning(tmp_path: Path) -> None:
    q = np.arange(704 * 2, dtype=np.float64).reshape(704, 2) / 1e4
    counts = np.arange(704 * 2, dtype=np.int64).reshape(704, 2) % 7
    meta = {
        "format": "tui-gym-agent", "version": 1, "env_id": "Blackjack-v1", "env_kwargs": {},
        "wrappers": [], "seed": 4, "episodes_trained": 900, "steps_trained": 1300,
        "agent_episode": 900, "n_actions": 2,
        "hyperparameters": {"learning_rate": 0.002, "discount": 1.0, "epsilon_start": 1.0,
                            "epsilon_final": 0.05, "epsilon_decay_fraction": 0.5,
                            "episodes": 2000, "learning_rate_schedule": "visits"},
    }
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("meta.json", json.dumps(meta))
        for member, array in (("q.npy", q), ("counts.npy", counts)):
            data = io.BytesIO()
            np.save(data, array)
            zf.writestr(member, data.getvalue())
    path = tmp_path / "old.tgym"
    path.write_bytes(buf.getvalue())
    session = Session.load(path)
    assert session.algorithm == "q-learning" and session.hp.learning_rate == 0.002
    assert np.array_equal(session.agent.q, q) and np.array_equal(session.agent.counts, counts)
    assert np.array_equal(session.agent.visits, counts.sum(axis=1))
    assert session.agent.episode == 900 and session.trainer.episodes == 900
