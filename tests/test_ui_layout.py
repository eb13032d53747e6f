"""The layout holds while people use it, at 120×40 and at 80×24.

The Train view's controls stay in sight whatever the engine note says; the
GridWorld board keeps its cell size while a person plays; the game picker
highlights the game shown; parameter names are never cut in the side panel,
where a person types them (the `wrappers` command's table is tested with the
CLI); escape leaves a text field; the wrapper chain shows its order and
parameters and can be reordered from the keyboard.
"""

from __future__ import annotations

from textual.widgets import Checkbox, Input, Label, RadioButton, RadioSet

from tui_gym.algorithms import QLearning
from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.help_screen import HelpScreen
from tui_gym.ui.side_panel import ParamField
from tui_gym.ui.widgets.grid_board import choose_shape

from .screen import screen_text
from .waiting import DEADLINE, wait_for

SIZES = [(120, 40), (80, 24)]


def app_for(game: str, episodes: int | None = None) -> TuiGymApp:
    hp = None if episodes is None else QLearning.hyperparameters(episodes=episodes)
    return TuiGymApp(Session(game, hp=hp, seed=0))


def inside(app: TuiGymApp, selector: str) -> bool:
    """Whether the widget is wholly on screen."""
    region = app.query_one(selector).region
    return bool(region.height) and app.screen.region.contains_region(region)


async def laid_out(pilot) -> None:
    """Wait until every parameter field has room for its whole name (a busy machine lays the
    side panel out a few frames after a new size)."""
    app = pilot.app
    await wait_for(pilot, lambda: all(f.query_one(Label).region.width >= len(f.param.name)
                                      for f in app.query(ParamField)), "the side panel")


def names_whole(app: TuiGymApp) -> None:
    """Every parameter field shows its whole name beside (or above) a usable input."""
    fields = list(app.query(ParamField))
    assert {"repeat_action_probability", "step_penalty"} <= {f.param.name for f in fields}
    for field in fields:
        label = field.query_one(Label)
        assert str(label.render()) == field.param.name
        assert label.region.width >= len(field.param.name), field.param.name
        box = field.query_one(Checkbox if field.param.kind is bool else Input)
        assert box.region.width >= 7


async def test_board_names_side_panel_and_train_controls_hold_while_people_use_it():
    """One app for the three: GridWorld's board and the names through the sizes, the
    side panel by keyboard (which ends on Blackjack), then Blackjack's Train view
    controls whatever the engine says, at both sizes."""
    app = app_for("gridworld")
    async with app.run_test(size=SIZES[0]) as pilot:
        await board_keeps_its_cells_and_names_stay_whole(pilot)
        await the_side_panel_by_keyboard(pilot)
        await train_controls_stay_in_sight_whatever_the_engine_says(pilot)


async def board_keeps_its_cells_and_names_stay_whole(pilot) -> None:
    """At 120×40, resized to 80×24 and back: at each size keys leave the cells as they
    are, and each resize picks the largest shape that fits."""
    app = pilot.app
    await pilot.pause()
    board = app.play_view.board

    def shape() -> tuple:
        drawn = board.layout_drawn.shape
        return (drawn.cell_w, drawn.cell_h, drawn.frame, drawn.axes)

    async def resize(width: int, height: int) -> None:
        await pilot.resize_terminal(width, height)
        await pilot.pause()  # the app takes a new size on a timer
        canvas = board.canvas.content_size
        best = choose_shape(5, 5, canvas.width, canvas.height)
        assert shape() == (best.cell_w, best.cell_h, best.frame, best.axes), (width, height)

    kept = {}  # the shape each size drew
    for size in SIZES:
        if size != SIZES[0]:
            await resize(*size)  # a new terminal size: the largest shape that fits
        await laid_out(pilot)
        names_whole(app)
        shapes = {shape()}
        # Advice, the coach, moves, a reset and the watched agent change the lines
        # around the board; the cells stay as they are.
        for key in ("i", "c", "right", "down", "r", "A", "x"):
            await pilot.press(key)
            shapes.add(shape())
        assert len(shapes) == 1, (size, shapes)
        kept[size] = shape()
    # And back, the other way: the largest that fits, the shape drawn there before.
    await resize(*SIZES[0])
    await laid_out(pilot)
    names_whole(app)
    assert shape() == kept[SIZES[0]]


async def the_side_panel_by_keyboard(pilot) -> None:
    """At 120×40: the picker highlights the game shown; the chain lists order and
    parameters and `[` / `]` reorder it; escape leaves a field (dropping an edit) for
    the view."""
    app = pilot.app
    assert app.size == (120, 40)
    await pilot.pause()
    picker = app.query_one("#game-picker", RadioSet)

    def highlighted() -> list[str]:
        return [b.id for b in picker.query(RadioButton) if b.has_class("-selected")]

    assert picker.pressed_button.id == "game-gridworld"
    assert highlighted() == ["game-gridworld"]
    assert not app.query_one("#game-blackjack", RadioButton).value

    # Escape leaves a text field: the edit not applied is dropped.
    size = app.query_one("#env-params").query_one(Input)
    await pilot.click(size)
    assert app.focused is size
    await pilot.press("end", "backspace", "9", "escape")
    assert app.focused is app.play_view.board
    assert size.value == "5" and app.session.env_kwargs["size"] == 5

    # The chain, in order, with parameters; [ and ] move the focused wrapper.
    await pilot.press("W", "space")  # the wrapper panel (w walks up here): TimeLimit
    app.query_one("#wrapper-StepPenalty").query_one(Checkbox).value = True
    await pilot.pause()
    assert [c.name for c in app.session.choices] == ["TimeLimit", "StepPenalty"]
    chain = str(app.query_one("#chain").render())
    assert "1 TimeLimit\n    max_episode_steps=100\n2 StepPenalty\n    penalty=0.01" in chain
    assert "StepPenalty  #2" in str(
        app.query_one("#wrapper-StepPenalty").query_one(Checkbox).label)
    app.query_one("#wrapper-StepPenalty").query_one(Checkbox).focus()
    await pilot.press("left_square_bracket")
    assert [c.name for c in app.session.choices] == ["StepPenalty", "TimeLimit"]
    assert app.session.chain_repr().startswith("<TimeLimit<StepPenalty<")
    chain = str(app.query_one("#chain").render())
    assert chain.index("1 StepPenalty") < chain.index("2 TimeLimit")
    await pilot.press("left_square_bracket")  # already innermost: said, nothing changes
    assert any("already innermost" in n.message for n in app._notifications)
    await pilot.press("right_square_bracket")
    assert [c.name for c in app.session.choices] == ["TimeLimit", "StepPenalty"]
    app.query_one("#wrapper-ClipReward").query_one(Checkbox).focus()
    await pilot.press("right_square_bracket")  # not in the chain: said, nothing changes
    assert any("Tick ClipReward first" in n.message for n in app._notifications)
    assert [c.name for c in app.session.choices] == ["TimeLimit", "StepPenalty"]

    # Escape from the panel in the Train view gives the keyboard to the heatmap.
    await pilot.press("t", "W", "escape")
    assert app.focused is app.train_view.heatmap
    await pilot.press("b")
    assert picker.pressed_button.id == "game-blackjack"
    assert highlighted() == ["game-blackjack"]
    assert not app.query_one("#game-gridworld", RadioButton).value
    await pilot.press("w")  # the wrappers, not Blackjack's own check boxes above them
    assert app.focused is app.query_one("#wrapper-TimeLimit").query_one(Checkbox)
    await pilot.press("f1")
    rows = [row for _, rows in app.screen.sections for row in rows]
    assert any(key == "esc" and "text field" in text for key, text in rows)
    assert any(key == "[ / ]" for key, _ in rows)


async def train_controls_stay_in_sight_whatever_the_engine_says(pilot) -> None:
    """Blackjack at 120×40, then resized to 80×24: the controls stay in sight at both."""
    app = pilot.app
    assert app.session.game.name == "blackjack" and app.size == (120, 40)
    await pilot.press("escape", "t")  # out of the help, to the Train view
    app.query_one("#wrapper-FlattenObservation").query_one(Checkbox).value = True
    await pilot.pause()
    # A small budget (the note does not depend on it), applied when training starts.
    app.train_view.form.input("episodes").value = "300"
    await pilot.press("escape", "space")  # back to the view, and train (on the env)
    await wait_for(pilot, lambda: app.runner.finished and not app.runner.running,
                   "the budget to finish")
    assert app.runner.wait_idle(DEADLINE)
    assert app.session.trainer.episodes == 300
    view = app.train_view
    note = view.engine_note
    assert "FlattenObservation changes the observations" in note
    assert "changes the observations" not in view.stats.plain  # not wrapped over lines
    assert view.stats.tooltip == note
    for size in SIZES:
        if size != SIZES[0]:
            await pilot.resize_terminal(*size)
        view.heatmap.focus()  # the body scrolls to the heatmap; the controls stay
        await pilot.pause()
        if size == (120, 40):
            assert inside(app, "#train-engine")
            assert app.query_one("#train-engine").region.height == 1
            assert app.query_one("#train-engine").tooltip == note
        for selector in ("#train-controls", "#btn-toggle", "#btn-reset", "#train-progress"):
            assert inside(app, selector), (size, selector)
        assert "Start" in screen_text(app), size
    await pilot.press("f1")  # the whole note is in the help too
    assert isinstance(app.screen, HelpScreen)
    assert any(note == text for _, rows in app.screen.sections for _, text in rows)
