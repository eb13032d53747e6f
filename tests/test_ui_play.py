"""The Play view: play Blackjack hands and walk GridWorld.

Every test drives the view with Textual's pilot the way a person would (keys,
clicks) and checks both the game's state and the words on screen. Most mount the
view alone (`PlayHost`); what the app adds, the keyboard on the board from the
start, the keys it shares with the boards, game switches and the compact layout,
is checked through the real `TuiGymApp`. Sessions are seeded, so the hands dealt
and the grids drawn are the same on every run; no test sleeps.
"""

from __future__ import annotations

from collections.abc import Sequence

from textual.app import App, ComposeResult
from textual.widgets import Static

from tui_gym.core.wrappers import WrapperChoice
from tui_gym.games.blackjack.game import card_label
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.play_view import PlayView
from tui_gym.ui.widgets.board_kinds import board_class
from tui_gym.ui.widgets.boards import Board, BoardButton
from tui_gym.ui.widgets.cards_board import CardsBoard
from tui_gym.ui.widgets.grid_board import GridBoard

from .hosts import VIEW_SIZE, PlayHost
from .waiting import wait_for

BIG = (120, 40)
SMALL = (80, 24)


def make_app(env: str = "blackjack", choices: Sequence[WrapperChoice] = (), seed: int = 0):
    return TuiGymApp(Session(env_id=env, seed=seed, choices=tuple(choices)))


def make_host(env: str = "blackjack", choices: Sequence[WrapperChoice] = (), seed: int = 0):
    """The Play view alone, on the session `make_app` would make."""
    return PlayHost(Session(env_id=env, seed=seed, choices=tuple(choices)))


def shown(view: PlayView, selector: str) -> str:
    """The plain text a Static of the Play view shows."""
    return str(view.query_one(selector, Static).render())


def drawing(view: PlayView) -> str:
    """The plain text of the board's drawing."""
    assert view.board is not None
    return str(view.board.canvas.render())


def path_keys(view: PlayView, keys: dict[str, str]) -> list[str]:
    """Keys that walk the agent to the target by a shortest path (x first)."""
    assert view.game is not None
    scene = view.game.scene()
    (ax, ay), (tx, ty) = scene["agent"], scene["target"]
    dx, dy = tx - ax, ty - ay
    return [keys["right"] if dx > 0 else keys["left"]] * abs(dx) + [
        keys["up"] if dy > 0 else keys["down"]
    ] * abs(dy)


ARROWS = {"right": "right", "left": "left", "up": "up", "down": "down"}
WASD = {"right": "d", "left": "a", "up": "w", "down": "s"}


# --- Blackjack ------------------------------------------------------------------


async def test_blackjack_hand_played_to_the_end_by_keys_buttons_and_clicks() -> None:
    app = make_host("blackjack")
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert game is not None and isinstance(view.board, CardsBoard)
        assert app.focused is view.board
        assert not game.done
        picture = drawing(view)
        assert "░" in picture and "showing" in picture, "the hole card lies face down"
        assert "New hand" in shown(view, "#play-headline")

        for _ in range(12):  # hit until the hand ends (a bust), or stick at 17+
            if game.done:
                break
            total = game.last.observation[0]
            await pilot.press("h" if total < 17 else "s")
        assert game.done and game.last is not None

        headline = shown(view, "#play-headline")
        reward = game.last.reward
        if reward > 0:
            assert headline.startswith("You win +")
        elif reward < 0:
            assert headline.startswith("Dealer wins −")
        else:
            assert headline.startswith("Push 0")
        assert game.tally.episodes == 1
        assert "Hands 1" in shown(view, "#play-tally")

        picture = drawing(view)
        dealer = game.scene()["dealer"]
        assert "░" not in picture and "showing" not in picture, "the hole card is revealed"
        assert card_label(dealer[1]) in picture

        # A move after the end only says what to do.
        await pilot.press("h")
        assert "This hand is over" in shown(view, "#play-hint")
        assert game.tally.episodes == 1

        # n deals the next hand; the tally keeps the first.
        await pilot.press("n")
        assert not game.done and game.last.steps == 0
        assert "░" in drawing(view)
        assert "New hand" in shown(view, "#play-headline")
        assert "Hands 1" in shown(view, "#play-tally")

        # The buttons work with the mouse (the same view: a fresh hand is dealt).
        hit, stick, deal = view.board.query(BoardButton)
        assert deal.disabled and not hit.disabled

        cards = len(game.scene()["player"])
        await pilot.click(hit)
        assert game.last.steps == 1
        assert game.done or len(game.scene()["player"]) == cards + 1
        if not game.done:
            await pilot.click(stick)
        assert game.done
        assert hit.disabled and stick.disabled and not deal.disabled
        assert app.focused is view.board, "clicking a button leaves the keyboard on the board"

        await pilot.click(deal)
        assert not game.done and game.tally.episodes == 2

        # Clicking the table gives the board the keyboard back.
        app.set_focus(None)
        await pilot.pause()
        assert view.board.border_subtitle == "click here to play"
        await pilot.click(view.board.canvas)
        assert app.focused is view.board
        assert not view.board.border_subtitle
        await pilot.press("s")
        assert view.game.done


async def test_blackjack_stick_enter_and_running_tally() -> None:
    app = make_host("blackjack", seed=3)
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert game is not None

        player = list(game.scene()["player"])
        await pilot.press("enter")  # dealing in the middle of a hand is refused gently
        assert "Finish this hand first" in shown(view, "#play-hint")
        assert game.scene()["player"] == player and not game.done

        returns = []
        for _ in range(5):
            await pilot.press("s")
            assert game.done
            returns.append(game.last.reward)
            await pilot.press("enter")
        tally = game.tally
        assert tally.episodes == 5
        assert tally.wins == sum(r > 0 for r in returns)
        assert tally.losses == sum(r < 0 for r in returns)
        assert tally.draws == sum(r == 0 for r in returns)
        text = shown(view, "#play-tally")
        assert "Hands 5" in text and f"wins {tally.wins}" in text
        assert f"losses {tally.losses}" in text and "95% CI" in text


# --- GridWorld ------------------------------------------------------------------


async def test_gridworld_walk_by_arrows_wasd_and_clicks_and_reset() -> None:
    app = make_host("gridworld")
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert game is not None and isinstance(view.board, GridBoard)
        assert app.focused is view.board

        for keys in (ARROWS, WASD):
            optimal = game.first_info["distance"]
            assert "optimal" in shown(view, "#play-detail")
            path = path_keys(view, keys)
            assert len(path) == optimal
            await pilot.press(*path)
            assert game.done and game.last.terminated and not game.last.truncated
            steps = f"{optimal} step{'' if optimal == 1 else 's'}"
            assert shown(view, "#play-headline").startswith(
                f"Reached the target in {steps} (optimal {optimal})"
            )
            assert app.focused is view.board, "the moves kept the keyboard on the board"
            await pilot.press("r")
            assert not game.done and game.last.steps == 0
        assert game.tally.episodes == 2 and game.tally.wins == 2
        assert "Episodes 2" in shown(view, "#play-tally")

        # Up is up on screen, and the trail shows (the same view, a fresh episode).
        start = game.scene()["agent"]
        key = "up" if start[1] < game.scene()["size"] - 1 else "down"
        row_before = _agent_row(drawing(view))
        await pilot.press(key)
        assert game.scene()["agent"][1] == start[1] + (1 if key == "up" else -1)
        row_after = _agent_row(drawing(view))
        assert (row_after < row_before) == (key == "up"), "+y is drawn upwards"
        assert ("↑" if key == "up" else "↓") in drawing(view), "the cell left shows the move"

        # r resets mid-episode.
        await pilot.press("r")
        await pilot.press(path_keys(view, ARROWS)[0])
        assert game.last.steps == 1
        await pilot.press("r")
        assert game.last.steps == 0 and not game.done
        assert game.tally.episodes == 2, "an unfinished episode is not counted"
        assert "New episode" in shown(view, "#play-headline")

        # A click on a cell steps towards it.
        board = view.board
        optimal = game.first_info["distance"]
        for _ in range(optimal):
            layout = board.layout_drawn
            assert layout is not None
            (x, y), size = game.scene()["target"], game.scene()["size"]
            await pilot.click(board.canvas, offset=layout.cell_center((size - 1 - y, x)))
        assert game.done and game.last.terminated and game.last.steps == optimal

        await pilot.click(board.query_one(BoardButton))  # ↺ Reset
        assert not game.done and game.last.steps == 0


async def test_a_move_in_mid_episode_leaves_the_agents_exact_figures_as_they_were() -> None:
    """The agent's table does not change while a person plays: its exact figures (a
    policy evaluation each, a tenth of a second on a maze) and the reason there are none
    are read when the view is shown and when an episode ends, never on every key."""
    app = make_host("gridworld")
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert game is not None
        # (the figures of the view being shown are computed on a thread: in before counting)
        await wait_for(pilot, lambda: view.agent_figures_shown, "the agent's exact figures")
        oracle = app.session.game.oracle
        asked: list[object] = []
        reference = oracle.reference

        def counted(*args: object, **kwargs: object) -> object:
            asked.append(args)
            return reference(*args, **kwargs)

        oracle.reference = counted  # type: ignore[method-assign]
        try:
            path = path_keys(view, ARROWS)
            assert len(path) > 1
            await pilot.press(*path[:-1])
            assert game.last.steps == len(path) - 1 and not game.done
            assert asked == [], "a move re-evaluated the agent"
            await pilot.press(path[-1])
            assert game.done
            await wait_for(pilot, lambda: bool(asked), "the episode's end reading the agent")
        finally:
            del oracle.reference


def _agent_row(picture: str) -> int:
    return next(i for i, line in enumerate(picture.splitlines()) if "●" in line)


async def test_gridworld_time_limit_truncates() -> None:
    app = make_host("gridworld", choices=(WrapperChoice.make("TimeLimit", max_episode_steps=3),))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        game = view.game
        assert "TimeLimit(3)" in shown(view, "#play-title")
        (ax, _), (tx, _) = game.scene()["agent"], game.scene()["target"]
        away = "left" if tx >= ax else "right"  # away from the target, into the wall
        await pilot.press(away, away, away)
        assert game.done and game.last.truncated and not game.last.terminated
        headline = shown(view, "#play-headline")
        assert headline.startswith("Truncated by the time limit after 3 steps")
        assert "Reached" not in headline
        assert "-even" in view.query_one("#play-status").classes
        tally = shown(view, "#play-tally")  # GridWorld's own words for how episodes end
        assert "reached 0" in tally and "timed out 1" in tally
        assert "wins" not in tally and "draws" not in tally and "losses" not in tally

        await pilot.press(away)  # a move after the end is refused gently
        assert "This episode is over" in shown(view, "#play-hint")


async def test_advice_shows_the_optimum_and_judges_moves() -> None:
    for env, keys in (("blackjack", ("s",)), ("gridworld", None)):
        app = make_host(env)
        async with app.run_test(size=VIEW_SIZE) as pilot:
            await pilot.pause()
            view = app.play_view
            assert "optimal:" not in shown(view, "#play-detail")
            await pilot.press("i")
            assert view.show_advice and "optimal:" in shown(view, "#play-detail")
            await pilot.press(*(keys or path_keys(view, ARROWS)[:1]))
            detail = shown(view, "#play-detail")
            assert "✓ optimal move" in detail or "✗ the optimum:" in detail
            if env == "gridworld":
                assert "✓ optimal move" in detail, "a step along a shortest path is optimal"


# --- what the app adds: its keys, game switches, sizes --------------------------


async def test_observation_wrappers_show_the_raw_observation() -> None:
    app = make_host("blackjack", choices=(WrapperChoice.make("FlattenObservation"),))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        await pilot.pause()
        view = app.play_view
        assert "observation: [" in shown(view, "#play-detail")
        await pilot.press("s")
        assert view.game.done


async def test_compact_layout_at_80x24_and_switching_games_swaps_the_board_keeps_focus() -> None:
    # One app at 80x24: Blackjack first, then GridWorld by its key, then back.
    app = make_app("blackjack")
    async with app.run_test(size=SMALL) as pilot:
        await pilot.pause()
        view = app.play_view
        assert app.focused is view.board, "the board has the keyboard from the start"
        mine, cards = view.game, view.board
        for env, key in (("blackjack", "h"), ("gridworld", "up")):
            if env == "gridworld":
                await pilot.press("g")
                await wait_for(pilot, lambda: isinstance(view.board, GridBoard)
                               and view.agent_figures_shown, "the grid and its exact figures")
                assert [b for b in view.query(Board) if b.display] == [view.board], "one shown"
                assert view.game.game.board == "grid"
                assert app.focused is view.board
                assert "GridWorld" in shown(view, "#play-title")
                keys = [key for key, _ in view.key_help()]
                assert "r" in keys
            assert app.screen.has_class("compact")
            board = view.board
            assert board is not None and board.region.height >= 7
            canvas = board.canvas.region
            assert canvas.height > 0 and canvas.width > 0
            assert app.screen.region.contains_region(view.query_one("#play-tally").region)
            picture = drawing(view)
            assert ("░" in picture) if env == "blackjack" else ("●" in picture)
            await pilot.press(key)
            await wait_for(pilot, lambda: view.game.last.steps == 1 or view.game.done, "the move")

        # w (the app's key for the wrappers) and r walk and reset on the grid.
        start, size = view.game.scene()["agent"], view.game.scene()["size"]
        await pilot.press("w")
        await wait_for(pilot, lambda: view.game.last.steps == 2, "the move up")
        agent = view.game.scene()["agent"]
        assert (agent[0], agent[1]) == (start[0], min(start[1] + 1, size - 1)), "w is up"
        assert app.focused is view.board, "w moved the agent; it did not leave the board"
        await pilot.press("r")
        await wait_for(pilot, lambda: view.game.last.steps == 0, "the reset")

        await pilot.press("b")
        await wait_for(pilot, lambda: isinstance(view.board, CardsBoard)
                       and app.focused is view.board, "the cards board with the keyboard")
        assert view.board is cards, "the cards board is shown again, not built again"
        assert view.game is mine and view.game.tally.episodes == 0, "the hand is kept"

        # n (the app's key for one training step) deals the next hand here.
        await pilot.press("s")
        await wait_for(pilot, lambda: view.game.done, "the hand's end")
        await pilot.press("n")
        await wait_for(pilot, lambda: not view.game.done, "the next hand")
        assert view.game.tally.episodes == 1
        assert app.focused is view.board


# --- the boards on their own (as the Train view uses them) ---------------------


class PassiveBoards(App[None]):
    def compose(self) -> ComposeResult:
        yield board_class("cards")(interactive=False)
        yield board_class("grid")(interactive=False)


async def test_passive_boards_draw_but_never_take_keys() -> None:
    app = PassiveBoards()
    async with app.run_test(size=(60, 30)) as pilot:
        cards, grid = app.query_one(CardsBoard), app.query_one(GridBoard)
        cards.show_scene({"player": [1, 6], "dealer": [10, 7], "player_total": 17,
                          "player_usable": True, "dealer_total": 17}, reveal=True)
        grid.show_scene({"size": 4, "agent": (0, 0), "target": (3, 3)}, reveal=True)
        await pilot.pause()
        assert not cards.focusable and not grid.focusable
        assert not cards.query(BoardButton)
        await pilot.press("h", "up")
        await pilot.pause()
        text = str(cards.canvas.render())
        assert "usable ace" in text and "17" in text and "Agent" in text
        assert "●" in str(grid.canvas.render()) and "◎" in str(grid.canvas.render())


async def test_shown_again_with_nothing_new_the_status_lines_are_left_as_they_are() -> None:
    app = make_host()
    async with app.run_test(size=VIEW_SIZE) as pilot:
        view = app.play_view
        await pilot.pause()
        headline = shown(view, "#play-headline")
        updates: list[str] = []
        for line in view.query("#play-status Static").results(Static):
            update = line.update
            line.update = (  # type: ignore[method-assign]
                lambda content="", *, layout=True, update=update, line=line:
                updates.append(str(line.id)) or update(content, layout=layout))
        view.on_show()  # back from another view: nothing happened meanwhile
        await pilot.pause()
        assert updates == [], "unchanged status lines were laid out again"
        view._say_hint("a hint")
        await pilot.pause()
        assert "play-hint" in updates
        assert shown(view, "#play-headline") == headline
