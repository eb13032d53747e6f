"""The coach, the advice, the scoreboard and watching the agent.

Each UI test drives the Play view with Textual's pilot as a person would and
checks the words on screen against exact figures computed independently
(the profile's advice values, the session's exact reference, the Tally's
interval). The view is mounted alone (`PlayHost`), except where the app's view
switch is the point. Sessions and deals are seeded; nothing sleeps: the watched
agent plays on a fast interval and the tests poll for what they wait on. The
last tests check `policy_steps_over_optimal` against a brute-force walk.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.gridworld_support import (
    mixed_steps_over_optimal,
    policy_steps_over_optimal,
    shortest_path_policy,
)
from tests.screen import drawn_text
from tui_gym.games.words import plural, signed
from tui_gym.session.play import HumanGame
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.play_view import WATCHING, PlayView
from tui_gym.ui.widgets.scoreboard import Scoreboard

from .hosts import VIEW_SIZE, PlayHost
from .waiting import wait_for

BIG = (120, 40)
FAST = 0.05  # seconds between the watched agent's moves in tests (faster starves the pilot)
DEADLINE = 10.0  # seconds a polled condition may take before the test fails

ARROW = {"right": "right", "up": "up", "left": "left", "down": "down"}
MOVES = {"right": (1, 0), "up": (0, 1), "left": (-1, 0), "down": (0, -1)}


def seed_for_first_hand(player_sum: int, usable: int) -> int:
    """A play seed whose first Blackjack hand is `player_sum` (usable ace or not)."""
    session = Session(env_id="blackjack")
    for seed in range(500):
        game = HumanGame(session, seed=seed)
        observation = game.reset().observation
        game.close()
        if (int(observation[0]), int(observation[2])) == (player_sum, usable):
            return seed
    raise AssertionError("no such seed")


def trained(env: str, episodes: int, seed: int = 0, **env_kwargs) -> Session:
    session = Session(env_id=env, seed=seed, env_kwargs=env_kwargs)
    session.trainer.run(episodes=episodes)
    return session


def shown(view: PlayView, selector: str) -> str:
    return str(view.query_one(selector).render())


def scoreboard_text(view: PlayView) -> str:
    return view.query_one(Scoreboard).text(compact=False)


def key_of(view: PlayView, action: int) -> str:
    """The key that makes `action` on the current board (Blackjack h/s, grid arrows)."""
    name = view.game.game.action_names[action]
    return {"hit": "h", "stick": "s"}.get(name, ARROW.get(name, name))


# --- the coach ----------------------------------------------------------------------


async def test_coach_prices_a_blunder_and_approves_the_optimum() -> None:
    seed = seed_for_first_hand(20, usable=0)
    app = PlayHost(Session(env_id="blackjack", seed=seed))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert not view.coach_on
        await pilot.press("c")
        assert view.coach_on and "coach on" in shown(view, "#play-title")

        advice = game.game.oracle.advice(game.env, app.session.env_kwargs)
        assert advice.optimal == (0,), "on a hard 20, stick is the optimum"
        cost = advice.values[0] - advice.values[1]
        assert cost > 0
        await pilot.press("h")  # hit a hard 20: a blunder
        await pilot.pause()
        coach = shown(view, "#play-coach")
        assert coach.startswith("✗ hit cost ")
        assert f"cost {cost:.3f} in expected return" in coach
        assert f"stick: {signed(advice.values[0], 3)}" in coach
        assert f"hit: {signed(advice.values[1], 3)}" in coach
        assert f"✗ hit cost {cost:.3f}" in drawn_text(app)

        if not game.done:  # drew an ace to 21: stick and finish
            await pilot.press("s")
        decisions = view.scorecard.decisions
        agreed = view.scorecard.agreed
        await pilot.press("n")
        assert shown(view, "#play-coach") == "", "a new hand starts without a verdict"
        advice = game.game.oracle.advice(game.env, app.session.env_kwargs)
        best = advice.optimal[0]
        await pilot.press(key_of(view, best))
        await pilot.pause()
        name = game.game.action_names[best]
        assert shown(view, "#play-coach") == f"✓ {name} was optimal"
        assert f"✓ {name} was optimal" in drawn_text(app)
        assert view.scorecard.decisions == decisions + 1
        assert view.scorecard.agreed == agreed + 1

        await pilot.press("c")  # off: the line goes, the counting goes on
        await pilot.pause()  # the screen read below drops the line
        assert not view.coach_on and "coach on" not in shown(view, "#play-title")
        assert shown(view, "#play-coach") == ""
        assert "was optimal" not in drawn_text(app)
        assert view.scorecard.decisions == decisions + 1, "toggling judges nothing"


async def test_coach_flags_moves_off_every_shortest_path() -> None:
    app = PlayHost(Session(env_id="gridworld", seed=1))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        await pilot.press("c")
        names = game.game.action_names

        def distance() -> int:
            scene = game.scene()
            (ax, ay), (tx, ty) = scene["agent"], scene["target"]
            return abs(ax - tx) + abs(ay - ty)

        def off_path_move() -> str:
            """A move off every shortest path that does not bump into a wall."""
            scene, size = game.scene(), game.scene()["size"]
            optimal = game.game.oracle.advice(game.env, app.session.env_kwargs).optimal
            for action, name in enumerate(names):
                dx, dy = MOVES[name]
                x, y = scene["agent"][0] + dx, scene["agent"][1] + dy
                if action not in optimal and 0 <= x < size and 0 <= y < size:
                    return name
            raise AssertionError("every move is optimal or blocked")

        start = distance()
        wrong = off_path_move()
        await pilot.press(ARROW[wrong])
        await pilot.pause()
        expected = f"✗ {wrong} is off every shortest path (now {start + 1} steps away, was {start})"
        assert shown(view, "#play-coach") == expected
        assert expected in drawn_text(app)
        assert view.scorecard.decisions == 1 and view.scorecard.agreed == 0

        while not game.done:  # walk home along a shortest path: every move approved
            optimal = game.game.oracle.advice(game.env, app.session.env_kwargs).optimal
            before = distance()
            await pilot.press(ARROW[names[optimal[0]]])
            coach = shown(view, "#play-coach")
            assert coach.startswith(f"✓ {names[optimal[0]]} is on a shortest path")
            to_go = f"{plural(before - 1, 'step')} to go" if before > 1 else "target reached"
            assert to_go in coach
        assert game.last.terminated and game.last.steps == start + 2
        assert view.scorecard.decisions == start + 2 and view.scorecard.agreed == start + 1
        assert view.scorecard.figure_mean("steps_over_optimal") == 2.0
        text = scoreboard_text(view)
        assert "2.00 steps over optimal (mean of 1 episode reached)" in text
        assert f"{start + 1}/{start + 2} moves on a shortest path" in text

        # The agent has learned nothing: advice says so, and its exact score is that of
        # what it does, a random walk (every action ties), cut off by the time limit.
        await pilot.press("r", "i")
        detail = shown(view, "#play-detail")
        assert "optimal: " in detail and "agent: has never seen this state" in detail
        size = game.scene()["size"]
        uniform = np.full((size,) * 4 + (4,), 0.25)
        extra, solved = mixed_steps_over_optimal(size, uniform, 300)
        await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's exact figures")
        assert view.agent_figures == {"steps_over_optimal": extra, "solved_fraction": solved}
        assert extra > 10 and 0.9 < solved < 1.0
        text = scoreboard_text(view)
        assert (f"{extra:.2f} steps over optimal, exact mean over the episodes its greedy "
                f"policy brings to the target ({solved:.1%} of them)") in text
        assert "Optimum  0 steps over optimal from every placement" in text


# --- advice: the optimum and the agent -------------------------------------------


async def test_advice_shows_the_optimum_and_the_agent() -> None:
    session = trained("blackjack", 3000)
    app = PlayHost(session)
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        await pilot.press("i")
        await pilot.pause()  # the screen read below shows the advice
        detail = shown(view, "#play-detail")
        advice = game.game.oracle.advice(game.env, session.env_kwargs)
        assert advice.note in detail
        choice = session.greedy_actions_for(game.last.observation)
        assert choice is not None, "3000 hands visit every opening state"
        ties, q = choice
        assert tuple(np.flatnonzero(q == q.max())) == ties
        picks = " or ".join(game.game.action_names[a] for a in ties)
        assert f"agent: {picks} (Q stick {signed(q[0], 3)}, hit {signed(q[1], 3)})" in detail
        screen = drawn_text(app)
        assert "agent: " in screen and "optimal: " in screen


# --- the scoreboard --------------------------------------------------------------


async def test_scoreboard_matches_the_tally_and_the_exact_reference() -> None:
    session = trained("blackjack", 2000, seed=4)
    app = TuiGymApp(session)
    async with app.run_test(size=BIG) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's exact figures")
        text = scoreboard_text(view)
        reference = session.reference().figures
        assert view.agent_figures["exact_value"] == reference["exact_value"]
        assert f"exact value {signed(reference['exact_value'], 4)} with its greedy policy" in text
        assert f"Optimum  exact value {signed(reference['optimal_value'], 4)}" in text
        assert "no hands played yet" in text
        screen = drawn_text(app)
        assert "Scoreboard" in screen and signed(reference["optimal_value"], 4) in screen

        optimal_moves = 0
        for hand in range(4):  # stick on the first two hands, follow the advice after
            while not game.done:
                advice = game.game.oracle.advice(game.env, session.env_kwargs)
                action = 0 if hand < 2 else advice.optimal[0]
                optimal_moves += action in advice.optimal
                steps = game.last.steps
                await pilot.press(key_of(view, action))
                await wait_for(pilot, lambda steps=steps: game.done or game.last.steps > steps,
                               "the move")
            # The hand's end has the agent's figures computed on a thread: in before the
            # next key, so the pilot's wait for an idle process holds for that key.
            await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's figures")
            if hand < 3:
                await pilot.press("n")
                await wait_for(pilot, lambda: not game.done, "the next hand")
        tally = game.tally
        assert tally.episodes == 4
        # Four hands say little about the interval's width: it shows as "–" (from 30 on).
        mean = f"mean return {signed(tally.mean, 3)} ± – (95% CI) over 4 hands"
        card = view.scorecard
        assert card.tally is tally and card.agreed == optimal_moves
        share = f"{card.agreed}/{card.decisions} optimal decisions ({card.agreement:.0%})"
        text = scoreboard_text(view)
        assert f"You      {mean} · {share}" in text
        await pilot.pause()  # the screen read below shows the last hand's figures
        assert "± – (95% CI)" in drawn_text(app)

        # The agent learns on: the figures follow when the Play view is shown again.
        await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's exact figures")
        session.trainer.run(episodes=500)
        exact = session.reference().figures["exact_value"]
        assert view.agent_figures["exact_value"] != exact, "500 more hands moved the value"
        await pilot.press("t")
        await pilot.pause()  # the Play view is hidden
        await pilot.press("p")
        await wait_for(
            pilot, lambda: view.agent_figures["exact_value"] == exact, "fresh agent figures"
        )
        assert f"exact value {signed(exact, 4)}" in scoreboard_text(view)


# --- watching the agent ----------------------------------------------------------


async def test_watching_the_agent_play_blackjack_and_taking_over() -> None:
    app = PlayHost(trained("blackjack", 2000))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        view.watch_interval, view.watch_pause_ticks = FAST, 1
        game = view.game
        mine = game.scene()
        assert "a / A" in dict(view.key_help())

        await pilot.press("a")
        await pilot.pause()
        assert view.watching and view.board.agent_playing
        assert WATCHING in drawn_text(app)
        assert view.board.scene == view.agent_game.scene()
        await wait_for(pilot, lambda: view.agent_game.tally.episodes >= 3, "three agent hands")
        assert game.tally.episodes == 0 and game.scene() == mine, "your hand is untouched"
        assert view.scorecard.decisions == 0
        assert "Agent" in str(view.board.canvas.render())
        watched = view.agent_game.tally
        assert "Watched" in scoreboard_text(view)
        assert "the agent played" in scoreboard_text(view)

        await pilot.press("h")  # any key takes over, and is swallowed
        await pilot.pause()
        assert not view.watching and not view.board.agent_playing
        assert view._watch_timer is None
        assert game.last.steps == 0, "the key only took control back"
        assert view.board.scene == mine
        assert "Back to your hand" in shown(view, "#play-headline")
        assert WATCHING not in drawn_text(app)
        moves = view.agent_game.last.steps, watched.episodes
        for _ in range(10):
            await pilot.pause()
        assert (view.agent_game.last.steps, watched.episodes) == moves, "the agent has stopped"

        await pilot.press("h")  # now keys play again
        assert game.last.steps == 1 or game.done

        # A click on the board takes over too, and moves nothing.
        view.watch_interval = 60.0  # the agent's next hand holds still: so do the buttons
        last = game.last
        for target in ("canvas", "button"):
            await pilot.press("A")
            await pilot.pause()
            assert view.watching
            if target == "canvas":
                await pilot.click(view.board.canvas)
            else:  # Hit, Stick or Deal, whichever the agent's hand allows
                buttons = view.board.query("BoardButton")
                await pilot.click(next(b for b in buttons if not b.disabled))
            assert not view.watching, f"a click on the {target} takes over"
            assert game.last is last and game.tally.episodes == int(game.done)


async def test_watching_the_agent_walk_the_grid_with_shift_a() -> None:
    app = PlayHost(Session(env_id="gridworld", seed=1, env_kwargs={"size": 4}))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        view.watch_interval = FAST
        game = view.game
        assert dict(view.key_help())["A"].startswith("watch the agent play")

        await pilot.press("a")  # on the grid, a is a move (left), not watching
        assert not view.watching and game.last.steps == 1
        mine = game.scene()

        await pilot.press("A")
        assert view.watching
        seen = {tuple(view.board.scene["agent"])}
        await wait_for(
            pilot,
            lambda: seen.add(tuple(view.board.scene["agent"])) or len(seen) >= 3,
            "the agent to walk across the board",
        )
        assert view.agent_card.decisions >= 2, "the agent made the moves"
        screen = drawn_text(app)
        assert "Grid" in screen and WATCHING in screen

        await pilot.press("left")
        assert not view.watching and game.last.steps == 1 and game.scene() == mine
        assert view.board.scene["agent"] == mine["agent"]
        assert game.tally.episodes == 0 and view.scorecard.decisions == 1


# --- the agent's choice, from the live table or a snapshot --------------------------


def test_greedy_actions_for_reads_the_agent_or_a_snapshot() -> None:
    fresh = Session(env_id="blackjack")
    assert fresh.greedy_actions_for((15, 10, 0)) is None, "never seen"
    assert fresh.greedy_actions_for((15, 10, 0), fresh.trainer.snapshot()) is None
    assert fresh.greedy_actions_for("not an observation") is None

    session = trained("blackjack", 2000)
    live = session.greedy_actions_for((15, 10, 0))
    assert live is not None
    ties, q = live
    assert ties == tuple(np.flatnonzero(q == q.max()))
    key = session.keyer.key((15, 10, 0))
    assert np.array_equal(q, session.agent.values([key])[0])
    seen = session.greedy_actions_for((15, 10, 0), session.trainer.snapshot())
    assert seen is not None and seen[0] == ties and np.array_equal(seen[1], q)
    assert session.agent_figures(session.trainer.snapshot()) == session.agent_figures()


# --- the exact reference behind the GridWorld scoreboard --------------------------


def brute_force_steps(size: int, policy: np.ndarray, limit: int) -> tuple[float, float]:
    """One placement at a time: walk until arrival or `limit` steps."""
    extra, solved, total = [], 0, 0
    for ax in range(size):
        for ay in range(size):
            for tx in range(size):
                for ty in range(size):
                    if (ax, ay) == (tx, ty):
                        continue
                    total += 1
                    x, y, steps = ax, ay, 0
                    while (x, y) != (tx, ty) and steps < limit:
                        dx, dy = list(MOVES.values())[int(policy[x, y, tx, ty])]
                        x, y = min(max(x + dx, 0), size - 1), min(max(y + dy, 0), size - 1)
                        steps += 1
                    if (x, y) == (tx, ty):
                        solved += 1
                        extra.append(steps - abs(tx - ax) - abs(ty - ay))
    return (float(np.mean(extra)) if extra else float("nan")), solved / total


@pytest.mark.parametrize("seed", range(8))
def test_policy_steps_over_optimal_matches_a_brute_force_walk(seed: int) -> None:
    rng = np.random.default_rng(seed)
    policy = rng.integers(0, 4, size=(3,) * 4)
    if seed % 2:  # mostly optimal, with a few detours: longer solved walks
        policy = np.where(rng.random(policy.shape) < 0.8, shortest_path_policy(3), policy)
    extra, solved = policy_steps_over_optimal(3, policy)
    want_extra, want_solved = brute_force_steps(3, policy, limit=100)
    assert solved == pytest.approx(want_solved)
    if want_solved:
        assert extra == pytest.approx(want_extra)
    else:
        assert np.isnan(extra)
    capped = policy_steps_over_optimal(3, policy, max_steps=2)
    want = brute_force_steps(3, policy, limit=2)
    assert capped[1] == pytest.approx(want[1])


def test_policy_steps_over_optimal_edge_cases() -> None:
    assert policy_steps_over_optimal(5, shortest_path_policy(5)) == (0.0, 1.0)
    extra, solved = policy_steps_over_optimal(4, np.zeros((4,) * 4, dtype=np.int64))
    # Always right: solved exactly when the target is further right on the same row.
    assert (extra, solved) == (0.0, pytest.approx(4 * 6 / (16 * 15)))
    with pytest.raises(ValueError):
        policy_steps_over_optimal(3, np.zeros((2,) * 4, dtype=np.int64))
    with pytest.raises(ValueError):
        policy_steps_over_optimal(3, np.full((3,) * 4, 4, dtype=np.int64))
