"""Exact figures that agree with play: wrapped rewards, random tie-breaking, the 95% interval.

The exact optimum, the value of a policy and the advice are computed for the
game as its wrappers make it where that can be done exactly, and checked here
against games actually played (hands drawn from the model the engine trains
on, its rewards passed through the wrappers' own reward code, or
`Session.evaluate`, the `tui-gym eval` path). Where a
wrapper changes the game beyond them, nothing claims an optimum. An agent
that has not learned breaks its ties at random, and its exact figures are
those of what it does. Every sample is seeded.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.gridworld_support import (
    mixed_pair_fraction,
    mixed_steps_over_optimal,
    optimal_pair_fraction,
    policy_steps_over_optimal,
    shortest_path_policy,
)
from tests.mdp_support import sampled_returns
from tui_gym.algorithms import QLearning
from tui_gym.core.wrappers import parse_wrapper_spec
from tui_gym.games import game_for
from tui_gym.games.blackjack.solver import (
    POLICY_SHAPE,
    mixed_policy_value,
    optimal_policy,
    optimal_value,
    policy_value,
)
from tui_gym.games.words import MIN_CI_EPISODES, return_summary
from tui_gym.session.play import HumanGame, Tally
from tui_gym.session.protocol import JsonlPlayer
from tui_gym.session.session import Session

Z = 4.0  # standard errors a sampled mean may stray from the exact value


def session(env: str, *wrappers: str, **env_kwargs) -> Session:
    return Session(env_id=env, seed=0, env_kwargs=env_kwargs,
                   choices=tuple(parse_wrapper_spec(w) for w in wrappers))


def play_blackjack(session: Session, hit: np.ndarray, n: int, seed: int) -> np.ndarray:
    """Returns of `n` hands drawn from the model the session trains on (its rewards the
    wrappers' own code made), hitting with probability `hit` (indexed by observation)."""
    training = session.training
    assert training is not None and training.rows is not None
    rest, usable = np.divmod(training.rows, 2)
    total, dealer = np.divmod(rest, 11)
    p = hit[total, dealer, usable]
    policy = np.column_stack([1.0 - p, p])
    return sampled_returns(training.model, policy, n, np.random.default_rng(seed),
                           max_steps=30)


def assert_close(returns: np.ndarray, exact: float) -> None:
    error = returns.std(ddof=1) / math.sqrt(len(returns))
    assert abs(returns.mean() - exact) < Z * error + 1e-12, (returns.mean(), exact, error)


# --- Blackjack under reward wrappers ---------------------------------------------------


@pytest.mark.parametrize(
    ("wrappers", "env_kwargs"),
    [
        (("ScaleReward:factor=-2",), {}),
        (("StepPenalty:penalty=0.1",), {}),
        (("ClipReward:min_reward=-0.5,max_reward=0.5",), {"natural": True}),
        (("StepPenalty:penalty=0.05", "ScaleReward:factor=-1"), {"natural": True}),
    ],
    ids=["negative-scale", "step-penalty", "clip-natural", "penalty-then-flip"],
)
def test_wrapped_blackjack_figures_match_play(wrappers, env_kwargs) -> None:
    game = session("blackjack", *wrappers, **env_kwargs)
    profile = game.game.oracle
    scope = profile.scope(game.env_kwargs, game.changes)
    assert scope.exact and "exact with" in scope.note
    rules = profile.rules(game.env_kwargs, game.changes)
    best = optimal_policy(rules).astype(np.float64)
    assert_close(play_blackjack(game, best, 120_000, seed=1), optimal_value(rules))
    coin = np.full(POLICY_SHAPE, 0.5)  # an agent with no preference anywhere
    assert_close(play_blackjack(game, coin, 120_000, seed=2), mixed_policy_value(coin, rules))
    bare = profile.rules(game.env_kwargs)  # the bare game's optimum is not the wrapped one's
    assert optimal_value(rules) != pytest.approx(optimal_value(bare))


def seed_for_hard_20(game: Session) -> int:
    for seed in range(500):
        play = HumanGame(game, seed=seed)
        obs = play.reset().observation
        play.close()
        if (int(obs[0]), int(obs[2])) == (20, 0):
            return seed
    raise AssertionError("no such seed")


def test_a_negative_scale_flips_the_advice_and_the_hint() -> None:
    bare = session("blackjack")
    flipped = session("blackjack", "ScaleReward:factor=-100")
    seed = seed_for_hard_20(bare)
    for game, best in ((bare, "stick"), (flipped, "hit")):
        player = JsonlPlayer(game, seed=seed)
        player.handle('{"cmd": "reset"}')
        hint = player.handle('{"cmd": "hint"}')
        assert hint["optimal_actions"] == [best], hint
        assert "unwrapped_optimal_actions" not in hint
        values = hint["action_values"]
        assert max(values, key=values.get) == best
    # Losing every hand is the wrapped game's best: hit until bust, +100 each time.
    assert flipped.reference().figures["optimal_value"] == pytest.approx(100.0)


@pytest.mark.parametrize(
    ("env", "wrapper"),
    [("blackjack", "StickyAction"), ("blackjack", "TimeLimit:max_episode_steps=3"),
     ("gridworld", "StickyAction"), ("gridworld", "ScaleReward:factor=-1")],
)
def test_changes_beyond_the_exact_figures_claim_no_optimum(env: str, wrapper: str) -> None:
    game = session(env, wrapper)
    scope = game.game.oracle.scope(game.env_kwargs, game.changes)
    assert not scope.exact
    assert game.reference().scope == scope
    player = JsonlPlayer(game, seed=3)
    player.handle('{"cmd": "reset"}')
    hint = player.handle('{"cmd": "hint"}')
    assert hint["optimal_actions"] == [] and "action_values" not in hint
    assert hint["unwrapped_optimal_actions"], hint
    assert "optimal:" not in hint["note"]
    name = wrapper.split(":")[0]
    assert name in hint["note"] and name in scope.note


def test_a_time_limit_no_hand_reaches_changes_nothing() -> None:
    game = session("blackjack", "TimeLimit:max_episode_steps=20")
    assert game.game.oracle.scope(game.env_kwargs, game.changes).exact
    assert game.reference().figures["optimal_value"] == pytest.approx(
        session("blackjack").reference().figures["optimal_value"])


@pytest.mark.parametrize(
    ("wrappers", "env_kwargs", "exact", "note"),
    [
        ((), {}, True, ""),
        (("StepPenalty:penalty=0.1",), {}, True, ""),
        (("ScaleReward:factor=2",), {}, True, ""),
        (("DistanceShaping:k=0.5",), {}, True, ""),
        (("ScaleReward:factor=-1",), {}, False, "figures of the unwrapped game"),
        (("ClipReward:min_reward=-1,max_reward=0",), {}, False, "figures of the unwrapped game"),
        ((), {"reward_scale": -1.0}, False, "shortest-path figures"),
    ],
)
def test_gridworld_claims_shortest_paths_optimal_only_when_they_are(
    wrappers, env_kwargs, exact, note
) -> None:
    game = session("gridworld", *wrappers, **env_kwargs)
    scope = game.game.oracle.scope(game.env_kwargs, game.changes)
    assert scope.exact == exact and scope.note.startswith(note)
    play = HumanGame(game, seed=0)
    play.reset()
    advice = game.game.oracle.advice(play.env, game.env_kwargs)
    assert bool(advice.optimal) == exact and bool(advice.unwrapped_optimal) != exact


# --- an agent that has not learned plays at random -------------------------------------


def test_an_untrained_blackjack_agent_is_valued_as_it_plays() -> None:
    game = session("blackjack")
    exact = game.reference().figures["exact_value"]
    assert exact == pytest.approx(mixed_policy_value(np.full(POLICY_SHAPE, 0.5)))
    assert exact != pytest.approx(policy_value(np.zeros(POLICY_SHAPE, dtype=np.int8)))
    report = game.evaluate(episodes=8000, seed=5)  # what `tui-gym eval` plays
    assert abs(report.mean_return - exact) < Z * report.standard_error


def test_an_untrained_gridworld_agent_is_valued_as_it_plays() -> None:
    game = session("gridworld", size=3)
    figures = game.agent_figures()
    assert figures["solved_fraction"] == pytest.approx(1.0, abs=1e-5)  # within 300 steps
    report = game.evaluate(episodes=1000, seed=5)
    assert report.figures["success_rate"] == 1.0
    assert abs(report.figures["mean_steps_over_optimal"] - figures["steps_over_optimal"]) < 2.5


def test_a_half_trained_table_counts_its_ties_as_coin_tosses() -> None:
    game = Session(env_id="blackjack", seed=0, hp=QLearning.hyperparameters(episodes=2000))
    game.trainer.run(episodes=300)
    q = game.base_q()
    tied = q[:, 0] == q[:, 1]
    assert tied.any() and not tied.all()
    hit = game.game.oracle.hit_probability(q)
    assert set(np.unique(hit[hit > 0])) <= {0.5, 1.0}
    exact = game.reference().figures["exact_value"]
    assert exact == pytest.approx(mixed_policy_value(hit))
    assert_close(play_blackjack(game, hit, 120_000, seed=3), exact)


# --- GridWorld's random policies, against brute force ----------------------------------


def random_policy(size: int, seed: int) -> np.ndarray:
    """Action probabilities: some cells deterministic (loops possible), some mixed."""
    rng = np.random.default_rng(seed)
    probs = rng.random((size,) * 4 + (4,)) * (rng.random((size,) * 4 + (4,)) < 0.6)
    probs[probs.sum(axis=-1) == 0, 0] = 1.0
    return probs / probs.sum(axis=-1, keepdims=True)


def brute_force(size: int, probs: np.ndarray) -> tuple[float, float]:
    """Steps over optimal and solved fraction with no time limit, by linear algebra
    on each target's absorbing chain."""
    cells = size * size
    deltas = ((1, 0), (0, 1), (-1, 0), (0, -1))
    extras, reach_all = [], []
    for tx in range(size):
        for ty in range(size):
            target = tx * size + ty
            moves = np.zeros((cells, cells))
            for ax in range(size):
                for ay in range(size):
                    here = ax * size + ay
                    for a, (dx, dy) in enumerate(deltas):
                        nx = min(size - 1, max(0, ax + dx))
                        ny = min(size - 1, max(0, ay + dy))
                        moves[here, nx * size + ny] += probs[ax, ay, tx, ty, a]
            moves[target] = 0.0
            # Cells that can reach the target at all (others never do).
            can = np.zeros(cells, dtype=bool)
            can[target] = True
            for _ in range(cells):
                can |= (moves[:, can] > 0).any(axis=1)
            rest = [c for c in range(cells) if can[c] and c != target]
            m = np.eye(len(rest)) - moves[np.ix_(rest, rest)]
            reach = np.linalg.solve(m, moves[rest, target])
            steps = np.linalg.solve(m, reach)  # expected steps of the walks that arrive
            for c in range(cells):
                if c == target:
                    continue
                distance = abs(c // size - tx) + abs(c % size - ty)
                if c in rest:
                    i = rest.index(c)
                    reach_all.append(reach[i])
                    extras.append(steps[i] - distance * reach[i])
                else:
                    reach_all.append(0.0)
    return float(np.sum(extras) / np.sum(reach_all)), float(np.mean(reach_all))


def pair_fraction_by_paths(size: int, probs: np.ndarray) -> float:
    """The chance of a shortest path, by following every shortest path."""
    deltas = ((1, 0), (0, 1), (-1, 0), (0, -1))

    def chance(ax: int, ay: int, tx: int, ty: int) -> float:
        if (ax, ay) == (tx, ty):
            return 1.0
        total = 0.0
        for a, (dx, dy) in enumerate(deltas):
            nx, ny = min(size - 1, max(0, ax + dx)), min(size - 1, max(0, ay + dy))
            if abs(nx - tx) + abs(ny - ty) < abs(ax - tx) + abs(ay - ty):
                total += probs[ax, ay, tx, ty, a] * chance(nx, ny, tx, ty)
        return total

    pairs = [(ax, ay, tx, ty) for ax in range(size) for ay in range(size)
             for tx in range(size) for ty in range(size) if (ax, ay) != (tx, ty)]
    return float(np.mean([chance(*p) for p in pairs]))


@pytest.mark.parametrize("size", [2, 3])
def test_random_gridworld_policies_match_brute_force(size: int) -> None:
    probs = random_policy(size, seed=size)
    extra, solved = mixed_steps_over_optimal(size, probs)
    want_extra, want_solved = brute_force(size, probs)
    assert solved == pytest.approx(want_solved, abs=1e-9)
    assert extra == pytest.approx(want_extra, rel=1e-6)
    assert mixed_pair_fraction(size, probs) == pytest.approx(pair_fraction_by_paths(size, probs))


@pytest.mark.parametrize("limit", [None, 3, 300])
def test_deterministic_policies_score_the_same_either_way(limit: int | None) -> None:
    size = 4
    rng = np.random.default_rng(7)
    for policy in (shortest_path_policy(size), rng.integers(0, 4, (size,) * 4)):
        probs = np.eye(4)[policy]
        extra, solved = policy_steps_over_optimal(size, policy, limit)
        mixed_extra, mixed_solved = mixed_steps_over_optimal(size, probs, limit)
        assert mixed_solved == pytest.approx(solved)
        assert mixed_extra == pytest.approx(extra, nan_ok=True)
        assert mixed_pair_fraction(size, probs) == pytest.approx(
            optimal_pair_fraction(size, policy))


# --- the 95% interval needs episodes --------------------------------------------------


def test_the_interval_shows_from_thirty_episodes() -> None:
    tally = Tally()
    for _ in range(2):
        tally.add(1.0)
    assert "± – (95% CI) over 2 hands" in return_summary(tally, "hand")
    assert "0.000" not in return_summary(tally, "hand")
    for i in range(MIN_CI_EPISODES - 2):
        tally.add((-1.0) ** i)
    low, high = tally.confidence_interval()
    assert f"± {(high - low) / 2:.3f} (95% CI) over 30 hands" in return_summary(tally, "hand")
    assert f"± {(high - low) / 2:.3f} over 30 hands" in return_summary(tally, "hand", short=True)


def test_a_greedy_policy_is_valued_once_while_the_table_keeps_it(monkeypatch) -> None:
    """A live run's snapshots mostly keep their greedy policy: its exact figures are not
    computed again, and a new greedy policy gets its own."""
    import tui_gym.games.model as model_module

    valued: list[int] = []
    evaluate = model_module.evaluate
    monkeypatch.setattr(model_module, "evaluate",
                        lambda model, policy: valued.append(1) or evaluate(model, policy))
    session = Session("frozenlake", seed=0)
    oracle, kwargs = session.game.oracle, session.exact_kwargs()
    rng = np.random.default_rng(0)
    q = rng.uniform(0.1, 1.0, (16, 4))
    first = oracle.reference(q, kwargs).figures
    same = oracle.reference(q * 2.0, kwargs).figures  # other values, the same greedy moves
    assert same == first and len(valued) == 1
    other = np.roll(q, 1, axis=1)
    figures = oracle.reference(other, kwargs).figures
    assert len(valued) == 2 and figures != first
    assert oracle.reference(q, kwargs).figures == first  # each policy's figures are kept
    assert oracle.reference(other, kwargs).figures == figures
    assert len(valued) == 2


def test_the_optimums_marks_are_solved_once_for_every_snapshots_heatmap(monkeypatch) -> None:
    """Gambler's ladder is too long to keep (each rung is solved when asked for): its
    heatmap's optimal marks and the optimum's values are kept, so a live run's next
    snapshots solve nothing."""
    import tui_gym.core.mdp.optimum as model_module

    solved: list[int] = []
    solve = model_module.solve
    monkeypatch.setattr(model_module, "solve",
                        lambda *args, **kwargs: solved.append(1) or solve(*args, **kwargs))
    oracle = game_for("gambler").oracle  # what an earlier test kept there, put aside
    monkeypatch.setattr(oracle, "_kept", {})
    monkeypatch.setattr(oracle, "_references", {})
    session = Session("gambler", seed=0)
    session.trainer.run(episodes=50)
    first = session.heatmaps(session.trainer.snapshot())
    assert solved and first
    count = len(solved)
    session.trainer.run(episodes=50)
    assert session.heatmaps(session.trainer.snapshot()) and len(solved) == count
    # ... and nor does the exact reference of each new greedy policy (the optimum's values)
    session.reference(session.trainer.snapshot())
    count = len(solved)
    session.trainer.run(episodes=50)
    assert session.reference(session.trainer.snapshot()) is not None and len(solved) == count
