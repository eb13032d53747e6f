"""The side panel: pick the game and the algorithm, tick wrappers, edit them, see the chain."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

from rich.text import Text
from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.widget import AwaitMount
from textual.widgets import Checkbox, Input, Label, RadioButton, RadioSet, Static

from tui_gym.algorithms import ALGORITHMS
from tui_gym.core.params import typed_text
from tui_gym.core.wrappers import CATALOG, Param, WrapperChoice, format_wrapper_spec
from tui_gym.games import GAMES
from tui_gym.ui.widgets.hyperparameter_form import FieldValidator
from tui_gym.ui.widgets.text_field import TextField
from tui_gym.ui.widgets.tick_box import TickBox

if TYPE_CHECKING:
    from tui_gym.session.session import Session

OTHER = "game-other"  # the picker's button for an env the registry does not list


FIELD_WIDTH, COMPACT_FIELD_WIDTH = 12, 7  # the input beside a parameter's name


def _tip(param: Param) -> str:
    used = f"; used when {param.when[0]} is {typed_text(param.when[1])}" if param.when else ""
    return f"{param.help} ({param.describe_range()}{used})".strip()


class ParamField(Horizontal):
    """One labelled parameter input. A name too long to sit beside its input goes on
    a line of its own above it (`-stacked`): the name is what a person types
    after `--wrapper`, so it is never cut."""

    DEFAULT_CSS = f"""
    ParamField {{ height: 1; padding-left: 4; }}
    ParamField Label {{ width: 1fr; color: $text-muted; }}
    ParamField Input {{ width: {FIELD_WIDTH}; }}
    ParamField Checkbox {{ width: {FIELD_WIDTH}; }}
    ParamField.-stacked {{ layout: vertical; height: 2; }}
    ParamField.-unused Label, ParamField.-unused Input {{ color: $text-disabled; }}
    ParamField.-stacked Input, ParamField.-stacked Checkbox {{ margin-left: 2; }}
    Screen.compact ParamField {{ padding-left: 2; }}
    Screen.compact ParamField Input, Screen.compact ParamField Checkbox {{
        width: {COMPACT_FIELD_WIDTH};
    }}
    """
    SCOPED_CSS = False  # the compact rules start at Screen

    def __init__(self, param: Param, value: Any) -> None:
        super().__init__(classes="param-field")
        self.param = param
        self._value = value

    def compose(self) -> ComposeResult:
        yield Label(self.param.name)
        yield self._box(self._value)

    def _box(self, value: Any) -> Checkbox | Input:
        """The box for the parameter: a tick for a bool, a checked text field otherwise."""
        box: Checkbox | Input
        if self.param.kind is bool:
            box = TickBox("", value=bool(value), compact=True)
        else:
            box = TextField(value=typed_text(value), compact=True,
                            validators=[FieldValidator(self.param)],
                            validate_on=["changed", "submitted"])
        box.tooltip = _tip(self.param)
        return box

    @property
    def input(self) -> Input:
        return self.query_one(Input)

    def on_resize(self, event: events.Resize) -> None:
        self._fit_name()

    def _fit_name(self) -> None:
        field = COMPACT_FIELD_WIDTH if self.screen.has_class("compact") else FIELD_WIDTH
        self.set_class(len(self.param.name) > self.size.width - field - 1, "-stacked")

    def show_param(self, param: Param, value: Any) -> None:
        """Stand for `param` and show its value: the label and the box are kept, and the
        box is made anew only when the kind of box differs (a tick or a text field)."""
        if param != self.param:
            box = self.query_one(Checkbox if self.param.kind is bool else Input)
            same_kind = (param.kind is bool) == (self.param.kind is bool)
            self.param = param
            self.query_one(Label).update(param.name)
            if self.size.width:
                self._fit_name()
            if not same_kind:
                box.remove()
                self.mount(self._box(value))
                return
            box.tooltip = _tip(self.param)
            if isinstance(box, Input):
                box.validators = [FieldValidator(param)]
        self.set_value(value)
        if param.kind is not bool:
            self.input.validate(self.input.value)

    def set_value(self, value: Any) -> None:
        """Show a value (without counting as an edit)."""
        box: Checkbox | Input = self.query_one(Checkbox) if self.param.kind is bool else self.input
        shown = bool(value) if isinstance(box, Checkbox) else typed_text(value)
        if box.value != shown:
            with box.prevent(Checkbox.Changed, Input.Changed):
                box.value = shown

    def read(self) -> tuple[Any, str | None]:
        """(value, None) when valid, else (None, the reason); the input marks itself."""
        if self.param.kind is bool:
            return self.query_one(Checkbox).value, None
        self.input.validate(self.input.value)
        try:
            return self.param.parse(self.input.value), None
        except ValueError as exc:
            return None, str(exc)


class WrapperRow(Vertical):
    """A catalog entry: a checkbox, its lesson, its parameters, and why it may not fit.
    The lines for a parameter's error and the reason are made when there is one to
    show (most rows never have either, and every widget costs the panel at start)."""

    SCOPED_CSS = False  # the compact rule below starts at Screen
    DEFAULT_CSS = """
    WrapperRow { height: auto; margin-bottom: 1; }
    WrapperRow .summary { color: $text-muted; padding-left: 4; }
    WrapperRow .reason, WrapperRow .param-error { color: $error; padding-left: 4; display: none; }
    WrapperRow .-shown { display: block; }
    WrapperRow.-misfit Checkbox { color: $text-disabled; }
    Screen.compact WrapperRow .summary { display: none; }
    """

    def __init__(
        self, name: str, choice: WrapperChoice | None, reason: str | None, place: int = 0
    ) -> None:
        super().__init__(id=f"wrapper-{name}")
        self.spec = CATALOG[name]
        self.choice = choice
        self.reason = reason
        self.place = place  # 1 for the innermost wrapper of the chain; 0 when not in it
        self._said: dict[str, str | None] = {"reason": reason and f"✗ {reason}"}
        self.set_class(bool(reason), "-misfit", update=False)  # styled when mounted

    def _label(self) -> str:
        return f"{self.spec.name}  #{self.place}" if self.place else self.spec.name

    def show_place(self, place: int) -> None:
        """Say where in the chain this wrapper sits (0: not in it)."""
        if place != self.place:
            self.place = place
            self.query_one(Checkbox).label = self._label()

    def compose(self) -> ComposeResult:
        spec = self.spec
        box = TickBox(self._label(), value=self.choice is not None, compact=True)
        box.tooltip = spec.summary
        yield box
        yield Static(spec.summary, classes="summary", markup=False)
        values = self.choice.values() if self.choice else spec.defaults()
        for param in spec.params:
            yield ParamField(param, values.get(param.name, param.default))
        if self.reason:
            yield Static(Text(f"✗ {self.reason}"), classes="reason -shown")

    def set_state(self, choice: WrapperChoice | None, reason: str | None) -> None:
        """Show the session's choice for this wrapper and why it does not fit, if so."""
        self.choice = choice
        box = self.query_one(Checkbox)
        with box.prevent(Checkbox.Changed):
            box.value = choice is not None
        values = choice.values() if choice else self.spec.defaults()
        for field in self.query_children(ParamField):
            field.set_value(values.get(field.param.name, field.param.default))
        self.show_error(None)
        self.show_reason(reason)

    def show_error(self, error: str | None) -> None:
        """Say why a parameter's text is not valid (or clear the message)."""
        self._say("param-error", error)

    def show_reason(self, reason: str | None) -> None:
        self.reason = reason
        self.set_class(bool(reason), "-misfit")
        self._say("reason", reason and f"✗ {reason}")

    def _say(self, kind: str, text: str | None) -> None:
        """Show `text` on the row's error or reason line, made the first time it has one."""
        if self._said.get(kind) == text:
            return
        self._said[kind] = text
        widget = self.query_one_optional(f"WrapperRow > .{kind}", Static)
        if widget is None:
            if not text:
                return
            widget = Static(classes=kind)
            # The error line sits above the reason.
            before = self.query_one_optional("WrapperRow > .reason") if kind != "reason" else None
            self.mount(widget, before=before)
        widget.update(Text(text or ""))
        widget.set_class(bool(text), "-shown")

    def read(self) -> tuple[WrapperChoice | None, str | None]:
        """The choice this row stands for (None when unticked), or the reason it is invalid."""
        if not self.query_one(Checkbox).value:
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


def chain_text(session: Session) -> Text:
    """The env built (the game's, or the one an edited map plays on), then each
    chosen wrapper in order with its parameters (`key=value`, as `--wrapper` takes
    them), then Gymnasium's repr of the env."""
    skipped = {id(choice) for choice, _ in session.skipped}
    built = session.game.make_id(session.env_id, session.env_kwargs)
    text = Text(built, style="bold")
    if built != session.env_id:  # an edited map plays on another env
        text.append(f"  ({session.env_id}'s rules on the edited map)", style="dim")
    if not session.choices:
        text.append("  (no wrappers)", style="dim")
    for place, choice in enumerate(session.choices, 1):
        applied = id(choice) not in skipped
        text.append(f"\n{place} ", style="dim")
        text.append(choice.name, style="bold green" if applied else "")
        if not applied:
            text.append("  ✗ not applied", style="red")
        # One line a parameter, as `--wrapper` writes it: names are never cut.
        for pair in format_wrapper_spec(choice).partition(":")[2].split(","):
            if pair:
                text.append(f"\n    {pair}", style="green" if applied else "")
    text.append("\n" + session.chain_repr(), style="dim")
    if session.skipped:
        names = ", ".join(c.name for c, _ in session.skipped)
        text.append(f"\n(not applied: {names})", style="red")
    return text


class SidePanel(VerticalScroll):
    """Game, wrappers and the resulting chain; posts `Changed` when a person edits them."""

    SCOPED_CSS = False  # the compact rule below starts at Screen
    DEFAULT_CSS = """
    SidePanel { width: 44; border-left: tall $primary-background; padding: 0 1; }
    Screen.compact SidePanel { width: 34; }
    SidePanel .section { text-style: bold; color: $accent; margin-top: 1; }
    SidePanel #chain { padding: 0 0 1 0; }
    SidePanel RadioSet { width: 100%; height: auto; }
    SidePanel RadioSet > RadioButton.-on { text-style: bold; color: $text-accent; }
    SidePanel #algorithm-summary { color: $text-muted; }
    SidePanel #env-params, SidePanel #wrapper-list { height: auto; }
    SidePanel .field-error { color: $error; display: none; }
    SidePanel .field-error.-shown { display: block; }
    SidePanel Input.-invalid { border: tall $error; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("left_square_bracket", "move_wrapper(-1)", "Move in", key_display="[",
                tooltip="Move the focused wrapper one place in (earlier) in the chain"),
        Binding("right_square_bracket", "move_wrapper(1)", "Move out", key_display="]",
                tooltip="Move the focused wrapper one place out (later) in the chain"),
        Binding("escape", "leave", "Back", tooltip="Back to the view (drops an edit not applied)"),
    ]

    class Left(Message):
        """The person left the panel (escape): the view should take the keyboard."""

    class AlgorithmPicked(Message):
        """The person picked another algorithm (by registry name)."""

        def __init__(self, name: str) -> None:
            super().__init__()
            self.name = name

    class Changed(Message):
        """The person asked for a different game, env arguments or wrappers."""

        def __init__(
            self, env_id: str, env_kwargs: dict[str, Any], choices: tuple[WrapperChoice, ...]
        ) -> None:
            super().__init__()
            self.env_id = env_id
            self.env_kwargs = env_kwargs
            self.choices = choices

    def __init__(self, *, id: str | None = None) -> None:  # noqa: A002  (Textual's name)
        super().__init__(id=id)
        self._rows: AwaitMount | None = None  # the wrapper rows' mount, once started
        self._rows_in = False  # every row is mounted: they show the session and are read
        self._rows_stale = False  # the session changed while they were mounting

    def compose(self) -> ComposeResult:
        self._order = [c.name for c in self.session.choices]  # the chain, innermost first
        yield Static("Game", classes="section")
        with RadioSet(id="game-picker"):
            for button_id, title, _ in self._picker_games():
                yield RadioButton(title, id=button_id)
        yield Vertical(*self._env_fields(), id="env-params")
        yield Static("", id="env-error", classes="field-error")
        yield Static("Algorithm", classes="section")
        with RadioSet(id="algorithm-picker"):
            for cls in ALGORITHMS:
                yield RadioButton(cls.title, id=f"algorithm-{cls.name}")
        yield Static(self._algorithm_summary(), id="algorithm-summary")
        yield Static("Wrapper chain  (innermost first)", classes="section")
        yield Static(chain_text(self.session), id="chain")
        yield Static("Wrappers  ([ ] move the focused one)", classes="section")
        yield Vertical(id="wrapper-list")  # its rows come after the first frame

    def on_mount(self) -> None:
        self._check_game()
        self._check_algorithm()
        self.call_after_refresh(self._list_wrappers)

    def _list_wrappers(self) -> None:
        """The catalog's rows, made after the first frame: they sit below both pickers
        and are most of what the panel costs to build. Until they are all in, the
        session's own wrappers stand for them."""
        if self._rows is not None:
            return
        chosen, reasons = self._wrapper_states()
        rows = [WrapperRow(name, chosen.get(name), reasons.get(name), self._place(name))
                for name in CATALOG]
        self._rows = self.query_one("#wrapper-list", Vertical).mount_all(rows)
        self.call_later(self._rows_ready)

    @property
    def wrappers_listed(self) -> bool:
        """Whether the wrapper rows are all in (they come after the first frame)."""
        return self._rows_in

    async def _rows_ready(self) -> None:
        """Make the rows if they are not made yet, and wait until they are in and show
        the session as it is now."""
        self._list_wrappers()
        assert self._rows is not None
        await self._rows
        if not self._rows_in:
            self._rows_in = True
            if self._rows_stale:
                self._show_wrappers()

    def _algorithm_summary(self) -> str:
        cls = self.session.learner_class
        return f"{cls.summary}; target {cls.formula}"

    def _check_algorithm(self) -> None:
        """Press the session's algorithm in its picker (the change asks for nothing)."""
        picker = self.query_one("#algorithm-picker", RadioSet)
        button = picker.query_one(f"#algorithm-{self.session.algorithm}", RadioButton)
        if picker.pressed_button is not button:
            button.value = True
        self.query_one("#algorithm-summary", Static).update(self._algorithm_summary())

    def _place(self, name: str) -> int:
        return self._order.index(name) + 1 if name in self._order else 0

    def _env_values(self) -> dict[str, Any]:
        """Each of the game's parameters with the session's value (else its default)."""
        session = self.session
        return {p.name: session.env_kwargs.get(p.name, p.default) for p in session.game.params}

    def _env_fields(self) -> list[ParamField]:
        values = self._env_values()
        return self._mark_unused(
            [ParamField(p, values[p.name]) for p in self.session.game.params], values)

    @staticmethod
    def _mark_unused(fields: list[ParamField], values: dict[str, Any]) -> list[ParamField]:
        """`fields`, those that do not matter with the others' `values` dimmed."""
        for field in fields:
            field.set_class(not field.param.applies(values), "-unused")
        return fields

    def _picker_games(self) -> list[tuple[str, str, str]]:
        """(button id, label, env id) of every game the picker lists: the registered ones,
        each with its hotkey, and the session's own when it is another env."""
        games = [(f"game-{g.name}", f"{g.title} ({g.key})" if g.key else g.title, g.env_id)
                 for g in GAMES]
        game = self.session.game
        if not any(g is game for g in GAMES):
            games.append((OTHER, game.title, self.session.env_id))
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
        """Press the session's game in the picker, so the picker's own highlight moves
        to it too (the change it reports matches the session and asks for nothing)."""
        picker = self.query_one("#game-picker", RadioSet)
        game = self.session.game
        listed = self._picker_games()
        # Another env than the registry's has one button of its own, while it is played.
        other = next((title for button_id, title, _ in listed if button_id == OTHER), None)
        buttons = picker.query(f"#{OTHER}")
        if other is None:
            buttons.remove()
        elif buttons:
            buttons.first(RadioButton).label = other
        else:
            picker.mount(RadioButton(other, id=OTHER))
        mine = next(i for i, _, env_id in listed if game.matches(env_id))
        button = picker.query_one(f"#{mine}", RadioButton)
        if picker.pressed_button is not button:
            button.value = True

    @property
    def session(self):  # the app's Session
        return self.app.session  # type: ignore[attr-defined]

    def reload(self) -> None:
        """Show the session as it is now (after a rebuild, or to undo an invalid edit)."""
        self._order = [c.name for c in self.session.choices]
        self._check_game()
        self._check_algorithm()
        self._show_env_fields()
        self._show_wrappers()
        self._show_error("#env-error", None)
        self.query_one("#chain", Static).update(chain_text(self.session))

    def _show_env_fields(self) -> None:
        """The game's parameters with the session's values, in the fields already there
        (each retitled as needed); fields are added or removed only as their number differs."""
        env_box = self.query_one("#env-params", Vertical)
        fields = list(env_box.query_children(ParamField))
        values = self._env_values()
        params = self.session.game.params
        for place, param in enumerate(params):
            value = values[param.name]
            if place < len(fields):
                fields[place].show_param(param, value)
            else:
                fields.append(ParamField(param, value))
                env_box.mount(fields[-1])
        for field in fields[len(params):]:
            field.remove()
        self._mark_unused(fields[:len(params)], values)

    def _show_wrappers(self) -> None:
        """Each wrapper row shows the session's choice, its place and why it does not fit."""
        if not self._rows_in:
            self._rows_stale = self._rows is not None  # rows not yet made read it as made
            return
        chosen, reasons = self._wrapper_states()
        for row in self.query_one("#wrapper-list").query_children(WrapperRow):
            row.set_state(chosen.get(row.spec.name), reasons.get(row.spec.name))
            row.show_place(self._place(row.spec.name))

    async def focus_wrappers(self) -> None:
        """Move the keyboard focus to the first wrapper checkbox (a key that asks before
        the rows are in waits for them, and so do the keys after it)."""
        await self._rows_ready()
        boxes = self.query_one("#wrapper-list").query(Checkbox)  # not the game's own
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

    def _read_env_kwargs(self) -> dict[str, Any] | None:
        values: dict[str, Any] = {}
        first_error = None
        for field in self.query_one("#env-params").query(ParamField):
            value, error = field.read()
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
        """The ticked wrappers in chain order: the order kept so far, then any newly
        ticked one outermost."""
        if not self._rows_in:  # nothing edited yet
            return self.session.choices
        chosen: dict[str, WrapperChoice] = {}
        first_error = None
        for row in self.query(WrapperRow):
            for field in row.query(ParamField):
                field.read()  # marks every field, of a row ticked or not
            choice, error = row.read()
            row.show_error(error)
            if error:
                first_error = first_error or error
            elif choice is not None:
                chosen[choice.name] = choice
        if first_error:
            return None
        names = [n for n in self._order if n in chosen]
        names += [n for n in chosen if n not in names]
        return tuple(chosen[n] for n in names)

    # --- events ----------------------------------------------------------------
    @on(RadioSet.Changed, "#game-picker")
    def _game_picked(self, event: RadioSet.Changed) -> None:
        env_id = self._selected_env_id()
        if env_id != self.session.env_id:
            self.post_message(self.Changed(env_id, {}, self.session.choices))

    @on(RadioSet.Changed, "#algorithm-picker")
    def _algorithm_picked(self, event: RadioSet.Changed) -> None:
        event.stop()
        pressed = event.radio_set.pressed_button
        name = (pressed.id or "").removeprefix("algorithm-") if pressed is not None else ""
        if name and name != self.session.algorithm:
            self.post_message(self.AlgorithmPicked(name))

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
            row = next((a for a in field.ancestors if isinstance(a, WrapperRow)), None)
            if row is None:
                self._show_error("#env-error", error)
            else:
                row.show_error(error)

    def action_move_wrapper(self, step: int) -> None:
        """Move the wrapper whose row has the focus one place in (-1) or out (+1)."""
        focused = self.app.focused
        nodes = focused.ancestors_with_self if focused is not None else []
        row = next((node for node in nodes if isinstance(node, WrapperRow)), None)
        if row is None:
            self.app.notify("Focus a ticked wrapper first (w, then tab).", timeout=3)
            return
        name = row.spec.name
        if name not in self._order:
            self.app.notify(f"Tick {name} first: only wrappers in the chain have a place.",
                            timeout=3)
            return
        index = self._order.index(name)
        target = index + step
        if not 0 <= target < len(self._order):
            where = "innermost" if step < 0 else "outermost"
            self.app.notify(f"{name} is already {where}.", timeout=2)
            return
        self._order[index], self._order[target] = self._order[target], self._order[index]
        self._request()

    def action_leave(self) -> None:
        """Back to the view; an edit not applied (with enter) is dropped."""
        self.reload()
        self.post_message(self.Left())

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
