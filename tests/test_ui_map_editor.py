"""The map editor, driven like a person would: paint, undo and redo, the optimum following
each edit, the agent kept through edits that keep its states and reset on a resize; a
game without a map offers no map key. One app drives it all in turn.

Waits poll a condition with a deadline; nothing sleeps.
"""

from __future__ import annotations

from tui_gym.session.session import Session
from tui_gym.ui.app import TuiGymApp
from tui_gym.ui.train_view import TrainView
from tui_gym.ui.widgets.map_editor import MapCanvas, MapEditor

from .hosts import VIEW_SIZE, TrainHost
from .waiting import wait_for

DEADLINE = 20.0
SIZE = (80, 24)


class MapTrainHost(TrainHost):
    """The Train view alone, playing an edited map as the app does."""

    def rebuild_map(self, env_kwargs: dict) -> bool:
        self.session.rebuild(env_kwargs=env_kwargs)
        self.train_view.reload()
        return True


def status(editor: MapEditor) -> str:
    return str(editor.query_one("#editor-status").content)


async def test_paint_undo_and_the_optimum_on_a_small_cliff_and_a_game_without_a_map(
) -> None:
    """CliffWalking's rules on SFF/FFG: every step costs 1, so the optimum is minus the
    fewest steps (3), and with the goal walled off the whole 200-step limit. Then
    Blackjack, a game without a map, offers no map key."""
    session = Session("cliffwalking", env_kwargs={"layout": "SFF\nFFG\n"}, seed=0,
                      hp={"episodes": 1_000_000_000})
    app = TuiGymApp(session)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.press("m")
        view = app.query_one(TrainView)
        await wait_for(pilot, lambda: editing(view), "the editor")
        editor = view.editor
        assert editor is not None
        # The Train view showing again (its first frame, a view switch) keeps the keyboard
        # on the map while the editor is open.
        app.action_show_view("train")
        await pilot.pause()
        assert editor.canvas.has_focus
        assert "exact optimum -3.0000 return" in status(editor)

        await pilot.press("down", "right", "2")  # a wall at row 1, col 1: the top way is left
        assert app.session.game.cells(app.session.env_kwargs) == ["SFF", "FWG"]
        assert "exact optimum -3.0000 return" in status(editor)
        canvas = editor.query_one(MapCanvas)
        hit = next((x, y) for y in range(canvas.size.height) for x in range(canvas.size.width)
                   if (cell := canvas.cell_at(x, y)) is not None and cell[1:] == (0, 1))
        pad = canvas.content_region.offset - canvas.region.offset  # cell_at counts in content
        await pilot.click(MapCanvas, offset=(hit[0] + pad.x, hit[1] + pad.y))
        # The top way walled too: no way to the goal, so the whole 200-step limit.
        assert app.session.game.cells(app.session.env_kwargs) == ["SWF", "FWG"]
        assert "exact optimum -200.0000 return" in status(editor)
        assert "no goal can be reached" in status(editor)

        await pilot.press("u")
        assert editor.grid_map.cells == ("SFF", "FWG")
        assert "exact optimum -3.0000" in status(editor)
        await pilot.press("y", "u")
        assert editor.grid_map.cells == ("SFF", "FWG")

        # Animated (light on the machine, and a person can follow); training goes on while
        # editing.
        await pilot.press("minus", "minus", "space")
        await wait_for(pilot, lambda: app.session.trainer.steps > 0, "some training")
        agent = app.session.agent
        # A pit of +1 beside the start: falling in (one step, +1) beats walking (-3).
        await pilot.press("left", "down", "3")  # a hole at row 1, col 0, at the game's own cost
        await pilot.press("right_square_bracket", "enter")  # its reward up to +1
        assert editor.grid_map.reward_table() == {(1, 0): 1.0}
        assert "exact optimum +1.0000 return" in status(editor)
        assert app.session.agent is agent, "a reward edit keeps the agent"
        assert app.runner.running, "training goes on"

        await pilot.press("shift+right")  # a new size: the states mean other cells
        await wait_for(pilot, lambda: app.session.agent is not agent, "a fresh agent")
        assert editor.grid_map.size_text == "2x4"
        assert any("reset" in n.message for n in app._notifications)
        assert app.runner.running, "training goes on with the fresh agent"

        await pilot.press("space")
        await wait_for(pilot, lambda: not app.runner.running, "training to pause")
        await pilot.press("escape")
        assert not view.editing_map

        # A game without a map offers no map key: m does nothing there.
        await pilot.press("b")
        await wait_for(pilot, lambda: app.session.game.name == "blackjack", "Blackjack")
        await pilot.press("m")
        await pilot.pause()
        assert not view.editing_map
        assert not app.check_action("edit_map", ())


async def test_the_status_names_cells_as_the_axes_do_and_says_when_nothing_is_left() -> None:
    """GridWorld numbers its rows from the bottom up: the status says what the axes say.
    An undo past the first edit says there is nothing to undo, not "undone" again."""
    app = MapTrainHost(Session("gridworld", seed=0))
    async with app.run_test(size=VIEW_SIZE) as pilot:
        view = app.train_view
        assert await view.open_editor()  # what `m` does in the app
        await wait_for(pilot, lambda: editing(view), "the editor")
        editor = view.editor
        assert editor is not None
        await pilot.press("down", "down", "down", "right", "right")  # the map's row 3, col 2
        await wait_for(pilot, lambda: editor.cursor == (3, 2), "the cursor")
        assert editor.canvas.panels[0].row_labels[3] == "1"
        await wait_for(pilot, lambda: "row 1, col 2: floor" in status(editor), "the cell")
        await pilot.press("2")  # a wall there
        await wait_for(pilot, lambda: "wall at row 1, col 2" in status(editor), "the edit")
        await pilot.press("u")
        await wait_for(pilot, lambda: "· undone" in status(editor), "the undo")
        await pilot.press("u")
        await wait_for(pilot, lambda: "· nothing to undo" in status(editor), "nothing left")
        assert "undone" not in status(editor)


def editing(view: TrainView) -> bool:
    """The editor is open, its canvas mounted and focused (`m` mounts it)."""
    return view.editor is not None and any(c.has_focus for c in view.editor.query(MapCanvas))
