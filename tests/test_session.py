"""The session: games and aliases, rebuilding with wrappers, per-state views, evaluation."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tui_gym  # noqa: F401  (registers GridWorld)
from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games.blackjack import BlackjackGame as BlackjackProfile
from tui_gym.games.gridworld import GridWorldGame as GridWorldProfile
from tui_gym.session.session import Session, default_settings

W = WrapperChoice.make
GRID = "tui_gym/GridWorld-v0"


# -- games and aliases ----------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "env_id", "profile", "n_actions"),
    [
        ("blackjack", "Blackjack-v1", BlackjackProfile, 2),
        ("Blackjack-v1", "Blackjack-v1", BlackjackProfile, 2),
        (" BlackJack ", "Blackjack-v1", BlackjackProfile, 2),
        ("gridworld", GRID, GridWorldProfile, 4),
        (GRID, GRID, GridWorldProfile, 4),
        ("gymnasium_env/GridWorld-v0", "gymnasium_env/GridWorld-v0", GridWorldProfile, 4),
    ],
)
def test_session_for_each_game_and_alias(
    name: str, env_id: str, profile: type, n_actions: int
) -> None:
    session = Session(name)
    assert session.env_id == env_id
    assert isinstance(session.game, profile)
    assert session.agent.n_actions == n_actions
    assert session.keyer.dense
    assert session.hp == default_settings(session.game, "q-learning", session.env_kwargs)
    assert session.trainer.run(episodes=20) == 20


def test_env_kwargs_are_completed_and_checked() -> None:
    assert Session("gridworld", {"size": 3}).env_kwargs["size"] == 3
    assert Session("blackjack", {"sab": True}).env_kwargs == {"natural": False, "sab": True}
    with pytest.raises(ValueError, match="size"):
        Session("gridworld", {"size": 99})
    with pytest.raises(ValueError, match="'decks'"):
        Session("blackjack", {"decks": 6})


def test_unknown_env_is_a_value_error_naming_the_choices() -> None:
    with pytest.raises(ValueError) as caught:
        Session("NoSuchGame-v0")
    assert "blackjack" in str(caught.value) and "gridworld" in str(caught.value)
    with pytest.raises(ValueError, match="does not fit: its observation space is Box"):
        Session("CartPole-v1")


# -- rebuilding -----------------------------------------------------------------


def _trained(name: str = "blackjack", episodes: int = 200, **kwargs) -> Session:
    session = Session(name, seed=1, **kwargs)
    session.trainer.run(episodes=episodes)
    return session


@pytest.mark.parametrize(
    "choices",
    [
        (W("StepPenalty"),),
        (W("TimeLimit", max_episode_steps=5),),
        (W("StickyAction"), W("ScaleReward", factor=2.0), W("ClipReward")),
    ],
)
def test_rebuild_keeps_the_agent_when_observations_mean_the_same(choices: tuple) -> None:
    session = _trained()
    agent, q = session.agent, session.agent.q.copy()
    report = session.rebuild(choices=choices)
    assert report.kept_agent and "kept" in report.notice
    assert session.agent is agent and np.array_equal(session.agent.q, q)
    assert session.trainer.episodes == 200  # progress carries on
    assert session.applied == choices and session.choices == choices
    session.trainer.run(episodes=10)
    assert session.trainer.episodes == 210


def test_rebuild_keeps_a_gridworld_agent_under_reward_wrappers() -> None:
    session = _trained("gridworld", episodes=50)
    agent = session.agent
    report = session.rebuild(choices=(W("DistanceShaping"), W("TimeLimit", max_episode_steps=50)))
    assert report.kept_agent and session.agent is agent


@pytest.mark.parametrize(
    ("name", "change"),
    [
        ("blackjack", {"choices": (W("FlattenObservation"),)}),
        ("blackjack", {"choices": (W("DelayObservation"),)}),
        ("gridworld", {"choices": (W("FlattenObservation"),)}),
        ("gridworld", {"choices": (W("DelayObservation", delay=2),)}),
        ("gridworld", {"choices": (W("TimeAwareObservation"),)}),
        ("gridworld", {"env_kwargs": {"size": 4}}),
        ("gridworld", {"env_id": "blackjack"}),
    ],
)
def test_rebuild_resets_the_agent_with_a_notice_when_meaning_changes(
    name: str, change: dict
) -> None:
    session = _trained(name, episodes=30)
    old_agent = session.agent
    report = session.rebuild(**change)
    assert not report.kept_agent
    assert "reset" in report.notice
    assert session.agent is not old_agent
    assert session.agent.states_seen == 0 and session.trainer.episodes == 0
    assert session.agent.n_actions == session.env.action_space.n
    assert session.agent.n_states == session.keyer.n_states
    session.trainer.run(episodes=5)


def test_gridworld_size_change_gives_a_table_of_the_new_size() -> None:
    session = _trained("gridworld", episodes=10)
    session.rebuild(env_kwargs={"size": 3})
    assert session.keyer.n_states == 3**4 and session.agent.q.shape == (81, 4)
    assert session.env.observation_space["agent"].high.tolist() == [2, 2]


def test_a_misfit_wrapper_is_skipped_and_the_reason_given() -> None:
    session = _trained()
    agent = session.agent
    choices = (W("StepPenalty"), W("DistanceShaping"))
    report = session.rebuild(choices=choices)
    assert report.kept_agent and session.agent is agent
    assert [c.name for c, _ in report.skipped] == ["DistanceShaping"]
    reason = report.skipped[0][1]
    assert "info['distance']" in reason and reason in report.notice
    assert "Not applied" in report.notice
    assert session.skipped == report.skipped
    assert [c.name for c in session.applied] == ["StepPenalty"]
    assert session.choices == choices  # the choice is remembered, e.g. for a later GridWorld
    assert "DistanceShaping" not in session.chain_repr()


def test_time_aware_without_a_time_limit_is_skipped_on_blackjack() -> None:
    session = Session("blackjack", choices=(W("TimeAwareObservation"),))
    assert session.applied == ()
    assert "TimeLimit" in session.skipped[0][1]


def test_unknown_env_leaves_the_session_unchanged() -> None:
    session = _trained(choices=(W("StepPenalty"),))
    before = (session.env_id, session.env_kwargs, session.choices, session.agent, session.trainer,
              session.env, session.chain_repr())
    with pytest.raises(ValueError, match="unknown env"):
        session.rebuild(env_id="NoSuchGame-v0")
    with pytest.raises(ValueError, match="'size'"):
        session.rebuild(env_kwargs={"size": 5})
    after = (session.env_id, session.env_kwargs, session.choices, session.agent, session.trainer,
             session.env, session.chain_repr())
    assert after == before
    assert session.trainer.run(episodes=5) == 5  # the env was not closed underneath


def test_chain_repr_looks_like_gymnasiums() -> None:
    bare = Session("blackjack")
    assert bare.chain_repr() == str(gym.make("Blackjack-v1"))
    assert bare.chain_repr() == "<OrderEnforcing<PassiveEnvChecker<BlackjackEnv<Blackjack-v1>>>>"
    wrapped = Session("gridworld", choices=(W("FlattenObservation"), W("StepPenalty")))
    assert wrapped.chain_repr() == f"<StepPenalty<FlattenObservation{gym.make(GRID)}>>"


def test_make_env_builds_a_fresh_env_with_the_applied_wrappers() -> None:
    session = Session("gridworld", choices=(W("FlattenObservation"), W("DistanceShaping")))
    env = session.make_env()
    assert env is not session.env and str(env) == session.chain_repr()
    assert env.reset(seed=0)[0].shape == (4,)


# -- heatmaps and the exact reference -------------------------------------------


def test_heatmaps_and_reference_of_bare_envs() -> None:
    blackjack = _trained(episodes=500)
    panels = blackjack.heatmaps()
    assert panels is not None and [p.shape for p in panels] == [(10, 10), (10, 10)]
    ref = blackjack.reference()
    assert ref is not None and set(ref.figures) == {"exact_value", "optimal_value", "gap"}
    assert ref.figures["gap"] == pytest.approx(
        ref.figures["optimal_value"] - ref.figures["exact_value"]
    )
    assert ref.figures["gap"] >= -1e-12
    assert blackjack.hidden_reason() == ""

    grid = _trained("gridworld", episodes=50)
    panels = grid.heatmaps(focus=(1, 2))
    assert panels is not None and panels[0].shape == (5, 5)
    assert panels[0].labels[5 - 1 - 2][1] == "T"  # the target cell, +y drawn upwards
    assert 0.0 <= grid.reference().figures["optimal_pair_fraction"] <= 1.0


@pytest.mark.parametrize("name", ["blackjack", "gridworld"])
def test_flatten_observation_shows_the_same_table_as_the_bare_env(name: str) -> None:
    # FlattenObservation only reshapes: the same seed learns the same values, and the
    # heatmaps and the reference see through the wrapper to them.
    bare = _trained(name, episodes=150, engine="env")
    flat = _trained(name, episodes=150, choices=(W("FlattenObservation"),))
    assert flat.hidden_reason() == ""
    assert np.array_equal(flat.base_q(), bare.base_q())
    assert flat.reference() == bare.reference()
    for a, b in zip(flat.heatmaps(), bare.heatmaps(), strict=True):
        assert a.labels == b.labels
        assert np.array_equal(a.values, b.values, equal_nan=True)
    assert np.array_equal(flat.base_q(flat.trainer.snapshot()), flat.base_q())


@pytest.mark.parametrize(
    ("name", "choice"),
    [
        ("blackjack", W("DelayObservation")),
        ("gridworld", W("DelayObservation", delay=3)),
        ("gridworld", W("TimeAwareObservation")),
        ("gridworld", W("TimeAwareObservation", flatten=False, normalize_time=True)),
    ],
)
def test_history_dependent_observations_hide_the_per_state_views(
    name: str, choice: WrapperChoice
) -> None:
    session = _trained(name, episodes=20, choices=(choice,))
    assert session.base_keys() is None
    assert session.heatmaps() is None and session.reference() is None
    assert session.base_q() is None
    reason = session.hidden_reason()
    assert choice.name in reason and "history" in reason


# -- evaluation -----------------------------------------------------------------


def test_evaluate_is_deterministic_for_a_seed() -> None:
    session = _trained(episodes=300)
    a = session.evaluate(500, seed=11)
    b = session.evaluate(500, seed=11)
    assert a == b
    c = session.evaluate(500, seed=12)
    assert c != a
    # Evaluating does not touch the agent's own generator or table.
    state = session.agent.rng.bit_generator.state
    session.evaluate(50)
    assert session.agent.rng.bit_generator.state == state


def test_blackjack_evaluation_rates_sum_to_one() -> None:
    report = _trained(episodes=300).evaluate(1000, seed=3)
    rates = [report.figures[k] for k in ("win_rate", "draw_rate", "loss_rate")]
    assert all(0.0 <= r <= 1.0 for r in rates)
    assert sum(rates) == pytest.approx(1.0)
    assert report.episodes == 1000
    # Returns are -1, 0 or +1, so the mean is the win rate minus the loss rate.
    assert report.mean_return == pytest.approx(rates[0] - rates[2])


def test_evaluate_rejects_zero_episodes() -> None:
    with pytest.raises(ValueError, match="episodes"):
        Session("blackjack").evaluate(0)


def test_short_gridworld_training_solves_the_grid() -> None:
    session = Session("gridworld", seed=0)
    assert session.hp.discount < 1.0
    session.trainer.run(episodes=3000)
    report = session.evaluate(500, seed=1)
    assert report.figures["success_rate"] == 1.0
    assert report.mean_return == 1.0
    assert session.reference().figures["optimal_pair_fraction"] > 0.9


def test_a_run_short_of_the_bound_says_why_in_a_sentence() -> None:
    solved = Session("gridworld", seed=0)
    solved.train()
    assert solved.shortfall(solved.reference()) == ""
    # Too few episodes: the settings are why.
    early = Session("frozenlake", seed=0, hp=QLearning.hyperparameters(episodes=20))
    early.train()
    sentence = early.shortfall(early.reference())
    assert sentence.startswith("It ends short of the bound (gap <= ")
    assert "more episodes" in sentence
    # SARSA's safe path on CliffWalking: the game's lesson is why.
    safe = Session("cliffwalking", algorithm="sarsa", seed=0)
    safe.train()
    assert safe.game.lessons["sarsa"] in safe.shortfall(safe.reference())


def test_set_hyperparameters_keeps_the_table() -> None:
    session = _trained(episodes=100)
    q = session.agent.q.copy()
    session.set_hyperparameters(QLearning.hyperparameters(learning_rate=0.5, episodes=1000))
    assert session.agent.hp.learning_rate == 0.5 and np.array_equal(session.agent.q, q)
    session.reset_agent()
    assert session.agent.states_seen == 0 and session.trainer.episodes == 0
    assert session.agent.hp.learning_rate == 0.5


def test_blackjack_heatmap_cells_read_the_q_table() -> None:
    from tui_gym.games.blackjack.game import (
        ACTION_LETTERS,
        CHART_SUMS,
        DEALER_CARDS,
        BlackjackGame,
    )
    from tui_gym.games.blackjack.solver import BlackjackRules, optimal_policy

    game = BlackjackGame()
    states = game.states.base_observations({})
    q = np.random.default_rng(3).normal(size=(len(states), 2))
    panels = game.layout.heatmaps(q, {}, None, game.oracle.optimal_marks({}))
    best = optimal_policy(BlackjackRules())
    for panel, usable in zip(panels, (1, 0), strict=True):
        for r, player in enumerate(CHART_SUMS):
            for c, dealer in enumerate(DEALER_CARDS):
                qs = q[states.index((player, dealer, usable))]
                action = int(np.argmax(qs))
                assert panel.labels[r][c] == ACTION_LETTERS[action]
                assert panel.values[r, c] == qs.max()
                assert panel.marked[r, c] == (action != best[player, dealer, usable])


def test_an_animated_step_after_training_on_the_model_is_seeded() -> None:
    """The env loop takes over a run the model loop began: its first episode's
    placement comes from the session's seed, the same on every run, not from the OS."""
    firsts = []
    for _ in range(3):
        session = Session("gridworld", seed=3)
        session.trainer.run(episodes=300)
        assert session.trainer.engine == "model"
        session.trainer.step()
        assert session.trainer.engine == "env"
        firsts.append(repr(session.trainer.current_observation()))
    assert len(set(firsts)) == 1, firsts
