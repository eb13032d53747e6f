"""The side panel: pick the game, tick wrappers, edit their parameters, see the chain.

`SidePanel` shows the game picker with the game's own arguments, the whole
wrapper catalog as checkboxes (each with its one-line lesson, its parameter
fields and, when it does not fit the game, the reason), and the resulting
wrapper chain in Gymnasium's repr form. It never rebuilds anything itself: it
posts `SidePanel.Changed` and the app asks the Session, then calls `reload()`.
Invalid parameter text marks its field, says why, and is not applied.
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.validation import ValidationResult, Validator
from textual.widgets import Checkbox, Input, Label, RadioButton, RadioSet, Static

from tui_gym.core.wrappers import CATALOG, Param, WrapperChoice
from tui_gym.games import GAMES
from tui_gym.ui.widgets.tick_box import TickBox


def _value_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return f"{value:g}" if isinstance(value, float) else str(value)


class ParamValidator(Validator):
    """Checks field text with a `Param`, so the Input marks itself valid or invalid."""

    def __init__(self, param: Param) -> None:
        super().__init__()
        self.param = param

    def validate(self, value: str) -> ValidationResult:
        try:
            self.param.parse(value)
        except ValueError as exc:
            return self.failure(str(exc))
        return self.success()


class ParamField(Horizontal):
    """One labelled parameter input with its own error line."""

    DEFAULT_CSS = """
    ParamField { height: 1; padding-left: 4; }
    ParamField Label { width: 1fr; color: $text-muted; }
    ParamField Input { width: 12; }
    ParamField Checkbox { width: 12; }
    Screen.compact ParamField { padding-left: 2; }
    Screen.compact ParamField Input, Screen.compact ParamField Checkbox { width: 7; }
    """
    SCOPED_CSS = False  # the compact rules start at Screen

    def __init__(self, param: Param, value: Any, group: str) -> None:
        super().__init__(classes="param-field")
        self.param = param
        self.group = group  # "env" or a wrapper name
        self._value = value

    def compose(self) -> ComposeResult:
        yield Label(self.param.name)
        tooltip = f"{self.param.help} ({self.param.describe_range()})".strip()
        if self.param.kind is bool:
            box = TickBox("", value=bool(self._value), compact=True)
            box.tooltip = tooltip
            yield box
            return
        field = Input(
            value=_value_text(self._value),
            compact=True,
            validators=[ParamValidator(self.param)],
            validate_on=["changed", "submitted"],
        )
        field.tooltip = tooltip
        yield field

    @property
    def input(self) -> Input:
        return self.query_one(Input)

    def set_value(self, value: Any) -> None:
        """Show a value (without counting as an edit)."""
        if self.param.kind is bool:
            box = self.query_one(Checkbox)
            with box.prevent(Checkbox.Changed):
                box.value = bool(value)
            return
        with self.input.prevent(Input.Changed):
            self.input.value = _value_text(value)

    def read(self) -> tuple[Any, str | None]:
        """(value, None) when the text is valid, else (None, the reason)."""
        if self.param.kind is bool:
            return self.query_one(Checkbox).value, None
        try:
            return self.param.parse(self.input.value), None
        except ValueError as exc:
            return None, str(exc)


class WrapperRow(Vertical):
    """A catalog entry: a checkbox, its lesson, its parameters, and why it may not fit."""

    SCOPED_CSS = False  # the compact rule below starts at Screen
    DEFAULT_CSS = """
    WrapperRow { height: auto; margin-bottom: 1; }
    WrapperRow .summary { color: $text-muted; padding-left: 4; }
    WrapperRow .reason { color: $error; padding-left: 4; display: none; }
    WrapperRow .param-error { color: $error; padding-left: 4; display: none; }
    WrapperRow .param-error.-shown { display: block; }
    WrapperRow.-misfit .reason { display: block; }
    WrapperRow.-misfit Checkbox { color: $text-disabled; }
    Screen.compact WrapperRow .summary { display: none; }
    """

    def __init__(self, name: str, choice: WrapperChoice | None, reason: str | None) -> None:
        super().__init__(id=f"wrapper-{name}")
        self.spec = CATALOG[name]
        self.choice = choice
        self.reason = reason

    def compose(self) -> ComposeResult:
        spec = self.spec
        box = TickBox(spec.name, value=self.choice is not None, compact=True)
        box.tooltip = spec.summary
        yield box
        yield Static(spec.summary, classes="summary", markup=False)
        values = self.choice.values() if self.choice else spec.defaults()
        for param in spec.params:
            yield ParamField(param, values.get(param.name, param.default), spec.name)
        yield Static("", classes="param-error")
        yield Static(self._reason_text(), classes="reason")

    def on_mount(self) -> None:
        self.set_class(bool(self.reason), "-misfit")

    def _reason_text(self) -> Text:
        return Text(f"✗ {self.reason}" if self.reason else "")

    def set_state(self, choice: WrapperChoice | None, reason: str | None) -> None:
        """Show the session's choice for this wrapper and why it does not fit, if so."""
        self.choice = choice
        box = self.query_one(Checkbox)
        with box.prevent(Checkbox.Changed):
            box.value = choice is not None
        values = choice.values() if choice else self.spec.defaults()
        for field in self.query(ParamField):
            field.set_value(values.get(field.param.name, field.param.default))
        self.show_error(None)
        self.show_reason(reason)

    @property
    def ticked(self) -> bool:
        return self.query_one(Checkbox).value

    def show_error(self, error: str | None) -> None:
        """Say why a parameter's text is not valid (or clear the message)."""
        widget = self.query_one(".param-error", Static)
        widget.update(Text(error or ""))
        widget.set_class(bool(error), "-shown")

    def show_reason(self, reason: str | None) -> None:
        self.reason = reason
        self.set_class(bool(reason), "-misfit")
        self.query_one(".reason", Static).update(self._reason_text())

    def read(self) -> tuple[WrapperChoice | None, str | None]:
        """The choice this row stands for (None when unticked), or the reason it is invalid."""
        if not self.ticked:
            return None, None
        values: dict[str, Any] = {}
        for field in self.query(ParamField):
            value, error = field.read()
            if error:
                return None, error
            values[field.param.name] = value
        try:
            return WrapperChoice.make(self.spec.name, **values), None
        except ValueError as exc:
            return None, str(exc)


class SidePanel(VerticalScroll):
    """Game, wrappers and the resulting chain; posts `Changed` when a person edits them."""

    SCOPED_CSS = False  # the compact rule below starts at Screen
    DEFAULT_CSS = """
    SidePanel { width: 44; border-left: tall $primary-background; padding: 0 1; }
    Screen.compact SidePanel { width: 34; }
    SidePanel .section { text-style: bold; color: $accent; margin-top: 1; }
    SidePanel #chain { color: $success; padding: 0 0 1 0; }
    SidePanel #game-picker { width: 100%; height: auto; }
    SidePanel #env-params, SidePanel #wrapper-list { height: auto; }
    SidePanel .field-error { color: $error; display: none; }
    SidePanel .field-error.-shown { display: block; }
    SidePanel Input.-invalid { border: tall $error; }
    """

    class Changed(Message):
        """The person asked for a different game, env arguments or wrappers."""

        def __init__(
            self, env_id: str, env_kwargs: dict[str, Any], choices: tuple[WrapperChoice, ...]
        ) -> None:
            super().__init__()
            self.env_id = env_id
            self.env_kwargs = env_kwargs
            self.choices = choices

    def compose(self) -> ComposeResult:
        yield Static("Game", classes="section")
        with RadioSet(id="game-picker"):
            for button_id, title, _ in self._picker_games():
                yield RadioButton(title, id=button_id)
        yield Vertical(*self._env_fields(), id="env-params")
        yield Static("", id="env-error", classes="field-error")
        yield Static("Wrapper chain", classes="section")
        yield Static(Text(self._chain_text()), id="chain")
        yield Static("Wrappers  (first ticked = innermost)", classes="section")
        chosen, reasons = self._wrapper_states()
        with Vertical(id="wrapper-list"):
            for name in CATALOG:
                yield WrapperRow(name, chosen.get(name), reasons.get(name))

    def on_mount(self) -> None:
        self._check_game()

    def _env_fields(self) -> list[ParamField]:
        session = self.session
        return [
            ParamField(p, session.env_kwargs.get(p.name, p.default), "env")
            for p in session.game.params
        ]

    def _picker_games(self) -> list[tuple[str, str, str]]:
        """(button id, label, env id) of every game the picker lists: the registered ones,
        each with its hotkey, and the session's own when it is another env."""
        games = [(f"game-{g.name}", f"{g.title} ({g.key})" if g.key else g.title, g.env_id)
                 for g in GAMES]
        game = self.session.game
        if not any(g is game for g in GAMES):
            games.append(("game-other", game.title, self.session.env_id))
        return games

    def _wrapper_states(self) -> tuple[dict[str, WrapperChoice], dict[str, str | None]]:
        """Each chosen wrapper by name, and for every wrapper why it does not fit (if so)."""
        session = self.session
        chosen = {c.name: c for c in session.choices}
        reasons: dict[str, str | None] = {c.name: reason for c, reason in session.skipped}
        for name, spec in CATALOG.items():
            if name not in reasons and name not in chosen:
                reasons[name] = spec.fits(session.env)
        return chosen, reasons

    def _check_game(self) -> None:
        picker = self.query_one("#game-picker", RadioSet)
        game = self.session.game
        listed = self._picker_games()
        if [b.id for b in picker.query(RadioButton)] != [i for i, _, _ in listed]:
            picker.remove_children()  # another env joined or left the list
            picker.mount_all(RadioButton(title, id=button_id) for button_id, title, _ in listed)
        mine = next((i for i, _, env_id in listed if game.matches(env_id)), "")
        with picker.prevent(RadioSet.Changed, RadioButton.Changed):
            for button in picker.query(RadioButton):
                button.value = button.id == mine

    @property
    def session(self):  # the app's Session
        return self.app.session  # type: ignore[attr-defined]

    def reload(self) -> None:
        """Show the session as it is now (after a rebuild, or to undo an invalid edit)."""
        self._check_game()
        env_box = self.query_one("#env-params", Vertical)
        fields = list(env_box.query(ParamField))
        wanted = self.session.game.params
        if [f.param for f in fields] == list(wanted):
            for field in fields:
                field.set_value(self.session.env_kwargs.get(field.param.name))
        else:
            env_box.remove_children()
            env_box.mount_all(self._env_fields())
        chosen, reasons = self._wrapper_states()
        for row in self.query(WrapperRow):
            row.set_state(chosen.get(row.spec.name), reasons.get(row.spec.name))
        self._show_error("#env-error", None)
        self.query_one("#chain", Static).update(Text(self._chain_text()))

    def _chain_text(self) -> str:
        session = self.session
        text = session.chain_repr()
        if session.skipped:
            names = ", ".join(c.name for c, _ in session.skipped)
            text += f"\n(not applied: {names})"
        return text

    def focus_wrappers(self) -> None:
        """Move the keyboard focus to the first wrapper checkbox."""
        boxes = self.query(Checkbox)
        if boxes:
            boxes.first().focus()
            self.scroll_to_widget(boxes.first())

    # --- reading what the person asked for -----------------------------------
    def _show_error(self, selector: str, message: str | None) -> None:
        error = self.query_one(selector, Static)
        error.update(Text(message or ""))
        error.set_class(bool(message), "-shown")

    def _selected_env_id(self) -> str:
        picker = self.query_one("#game-picker", RadioSet)
        pressed = picker.pressed_button
        if pressed is None or pressed.id is None:
            return self.session.env_id
        return next((env_id for i, _, env_id in self._picker_games() if i == pressed.id),
                    self.session.env_id)

    def _mark(self, field: ParamField, error: str | None) -> None:
        if field.param.kind is not bool:
            field.input.validate(field.input.value)

    def _read_env_kwargs(self) -> dict[str, Any] | None:
        values: dict[str, Any] = {}
        first_error = None
        for field in self.query_one("#env-params").query(ParamField):
            value, error = field.read()
            self._mark(field, error)
            if error:
                first_error = first_error or error
            else:
                values[field.param.name] = value
        self._show_error("#env-error", first_error)
        # Arguments without a field (an edited map) stay as they are.
        kept = {k: v for k, v in self.session.env_kwargs.items()
                if k not in {p.name for p in self.session.game.params}}
        return None if first_error else {**kept, **values}

    def _read_choices(self) -> tuple[WrapperChoice, ...] | None:
        choices = []
        first_error = None
        for row in self.query(WrapperRow):
            for field in row.query(ParamField):
                self._mark(field, field.read()[1])
            choice, error = row.read()
            row.show_error(error)
            if error:
                first_error = first_error or error
            elif choice is not None:
                choices.append(choice)
        return None if first_error else tuple(choices)

    # --- events ----------------------------------------------------------------
    @on(RadioSet.Changed, "#game-picker")
    def _game_picked(self, event: RadioSet.Changed) -> None:
        env_id = self._selected_env_id()
        if env_id != self.session.env_id:
            self.post_message(self.Changed(env_id, {}, self.session.choices))

    @on(Checkbox.Changed)
    def _wrapper_ticked(self, event: Checkbox.Changed) -> None:
        event.stop()
        self._request()

    @on(Input.Submitted)
    def _param_submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self._request()

    @on(Input.Changed)
    def _param_typed(self, event: Input.Changed) -> None:
        """Mark an invalid value as it is typed (applied on enter)."""
        field = next((a for a in event.input.ancestors if isinstance(a, ParamField)), None)
        if field is not None:
            error = field.read()[1]
            self._mark(field, error)
            row = next((a for a in field.ancestors if isinstance(a, WrapperRow)), None)
            if row is None:
                self._show_error("#env-error", error)
            else:
                row.show_error(error)

    def _request(self) -> None:
        kwargs = self._read_env_kwargs()
        choices = self._read_choices()
        if kwargs is None or choices is None:
            self.app.notify("Not applied: fix the marked field.", severity="error", timeout=4)
            return
        session = self.session
        env_id = self._selected_env_id()
        if env_id == session.env_id and kwargs == session.env_kwargs and choices == session.choices:
            return
        self.post_message(self.Changed(env_id, kwargs, choices))
