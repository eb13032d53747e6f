"""The side panel mounted alone: its wrapper rows come after the first frame, and show the
session as it is once they are in."""

from __future__ import annotations

import asyncio

from textual.app import App, ComposeResult
from textual.widgets import Checkbox, Input, Label

from tui_gym.core.params import typed_text
from tui_gym.core.wrappers import WrapperChoice
from tui_gym.session.session import Session
from tui_gym.ui.side_panel import ParamField, SidePanel, WrapperRow

from .waiting import wait_until


class PanelHost(App[None]):
    """A `SidePanel` over `session`; as it mounts, a person presses `w` and a wrapper is
    chosen (the app reloads the panel after a rebuild) while the rows are being made."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session
        self.listed_at_mount: bool | None = None
        self.focusing: asyncio.Task[None] | None = None

    def compose(self) -> ComposeResult:
        yield SidePanel(id="side")

    async def on_mount(self) -> None:
        panel = self.query_one(SidePanel)
        self.listed_at_mount = panel.wrappers_listed
        self.focusing = asyncio.create_task(panel.focus_wrappers())
        await asyncio.sleep(0)  # it starts making the rows and waits for them
        self.session.rebuild(choices=(WrapperChoice("TimeLimit", (("max_episode_steps", 40),)),))
        panel.reload()


async def test_wrapper_rows_made_after_mounting_show_the_session_and_take_the_focus() -> None:
    app = PanelHost(Session("frozenlake", seed=0))
    async with app.run_test(size=(44, 40)) as pilot:
        panel = app.query_one(SidePanel)
        await wait_until(pilot, lambda: app.focusing is not None and app.focusing.done(),
                         "w's focus")
        assert app.listed_at_mount is False and panel.wrappers_listed
        row = app.query_one("#wrapper-TimeLimit", WrapperRow)
        box = row.query_one(Checkbox)
        assert box.value and str(box.label) == "TimeLimit  #1"
        assert row.query_one(ParamField).input.value == "40"
        assert not app.query_one("#wrapper-StepPenalty").query_one(Checkbox).value
        assert app.focused is box


class SwitchHost(App[None]):
    """A `SidePanel` over whichever session the test hands it."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session

    def compose(self) -> ComposeResult:
        yield SidePanel(id="side")


def env_fields(app: SwitchHost) -> list[ParamField]:
    return list(app.query_one("#env-params").query_children(ParamField))


async def test_a_game_switch_shows_the_new_games_fields_in_the_fields_already_there() -> None:
    # Frozen Lake (text, text, text, tick, text) to Cliff Walking (tick, text) to the
    # gambler (text, text) and back: fields change kind both ways, are retitled, removed
    # and added.
    frozen = Session("frozenlake", seed=0)
    app = SwitchHost(frozen)
    async with app.run_test(size=(44, 40)) as pilot:
        panel = app.query_one(SidePanel)
        first = env_fields(app)
        first[1].input.value = "x"  # an edit not applied, marked invalid
        assert first[1].input.has_class("-invalid")
        for session in (Session("cliffwalking", {"slippery": True}, seed=0),
                        Session("gambler", seed=0), frozen):
            app.session = session
            panel.reload()
            await pilot.pause()
            fields = env_fields(app)
            assert fields[:2] == first[:2]  # kept, whatever they show now
            assert [f.param for f in fields] == list(session.game.params)
            for field in fields:
                value = session.env_kwargs[field.param.name]
                label = str(field.query_one(Label).render())
                assert label == field.param.name
                if field.param.kind is bool:
                    box = field.query_one(Checkbox)
                    assert box.value is value and not field.query(Input)
                else:
                    box = field.input
                    assert box.value == typed_text(value) and not box.has_class("-invalid")
                    assert field.read()[1] is None
                assert str(box.tooltip).startswith(field.param.help)
        # A kept field checks a value by the parameter it shows now.
        first[1].input.value = "0"
        assert first[1].param.name == "size" and first[1].input.has_class("-invalid")


async def test_parameters_that_do_not_matter_with_the_others_are_dimmed() -> None:
    app = SwitchHost(Session("frozenlake", seed=0))  # the 4x4 map, slippery

    def dimmed() -> set[str]:
        return {f.param.name for f in app.query_one("#env-params").query(ParamField)
                if f.has_class("-unused")}

    async with app.run_test(size=(44, 40)) as pilot:
        assert dimmed() == {"size", "map_seed"}
        app.session.rebuild(env_kwargs={"map": "random", "size": 5, "slippery": False})
        app.query_one(SidePanel).reload()
        await pilot.pause()
        assert dimmed() == {"success_rate"}
