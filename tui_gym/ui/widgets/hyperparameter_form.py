"""The hyperparameter form: one checked field per knob of the algorithm in use."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, cast

from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.validation import ValidationResult, Validator
from textual.widget import Widget
from textual.widgets import Input, Label, Select, Static

from tui_gym.algorithms import Field, QLearning, Settings
from tui_gym.core.params import Param, ParamError, digits_note, read_number, typed_text
from tui_gym.ui.widgets.numbers import compact_count
from tui_gym.ui.widgets.strip_widget import panel_css
from tui_gym.ui.widgets.text_field import TextField

_SUPERSCRIPTS = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


def bound_text(value: float) -> str:
    """A bound, short: '1', '0.5', '1000', '10⁹', '12.3k'."""
    if not float(value).is_integer():
        return f"{value:g}"
    number = int(value)
    if abs(number) < 10_000:
        return str(number)
    digits = str(abs(number))
    if digits.strip("0") == "1":  # a power of ten
        return ("-" if number < 0 else "") + "10" + str(len(digits) - 1).translate(_SUPERSCRIPTS)
    return compact_count(number)


def range_hint(field: Param) -> str:
    """The accepted range, short enough for the hint column: '(0, 1]', '[1, 10⁹]',
    '±10⁶' (a range around 0, both ends in it)."""
    if field.minimum is None or field.maximum is None:
        return field.expected().split(" in ", 1)[-1]
    if field.minimum == -field.maximum and field.min_inclusive:
        return f"±{bound_text(field.maximum)}"
    low = ("[" if field.min_inclusive else "(") + bound_text(field.minimum)
    return f"{low}, {bound_text(field.maximum)}]"


def field_error(field: Param, text: str) -> str | None:
    """Why `text` is not a valid value of the field (None when it is), short enough to
    sit under it: '5' is above 1, '0' must be above 0, 'abc' is not a number in (0, 1]."""
    if not text.strip():
        return f"empty: needs {field.expected()}"
    try:
        field.parse(text.strip())
    except ParamError as exc:
        value = read_number(text)
        if not exc.out_of_range or value is None or math.isnan(value):
            return f"{exc.shown} is not {field.expected()}{digits_note(text)}"
        high = math.inf if field.maximum is None else field.maximum
        low = -math.inf if field.minimum is None else field.minimum
        if value > high or value == math.inf:
            return f"{exc.shown} is above {_full(high)}"
        if value == low and not field.min_inclusive:
            return f"{exc.shown} must be above {_full(low)}"
        return f"{exc.shown} is below {_full(low)}"
    return None


def _full(value: float) -> str:
    """'1,000,000,000', '0.5', 'every number' (no bound)."""
    if math.isinf(value):
        return "every number"
    return f"{int(value):,}" if float(value).is_integer() else f"{value:g}"


class FieldValidator(Validator):
    """Checks an Input against one hyperparameter's range."""

    def __init__(self, field: Param) -> None:
        super().__init__()
        self.field = field

    def validate(self, value: str) -> ValidationResult:
        problem = field_error(self.field, value)
        return self.success() if problem is None else self.failure(problem, value)


class HyperparameterForm(Vertical):
    """Labelled, range-checked inputs for the agent's hyperparameters."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = panel_css("HyperparameterForm") + """
    HyperparameterForm { width: 1fr; min-width: 38; max-width: 48; }
    HyperparameterForm .hp-row { height: 1; }
    HyperparameterForm .hp-label { width: 15; color: $text-muted; }
    HyperparameterForm Input { width: 1fr; min-width: 8; max-width: 14; }
    HyperparameterForm Input.-invalid { color: $text-error; text-style: bold; }
    HyperparameterForm .hp-hint { width: 10; padding-left: 1; color: $text-disabled; }
    HyperparameterForm .hp-error { display: none; color: $text-error; padding-left: 2; }
    HyperparameterForm .hp-error.-shown { display: block; }
    HyperparameterForm .hp-row.-invalid .hp-label { color: $text-error; text-style: bold; }
    Screen.compact HyperparameterForm { min-width: 0; max-width: 100%; }
    Screen.compact HyperparameterForm .hp-hint { display: none; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "leave", "Leave the fields", show=False),
    ]

    @dataclass
    class Submitted(Message):
        """Enter in a field: `hyperparameters` is None when some field is wrong."""

        form: HyperparameterForm
        hyperparameters: Settings | None

        @property
        def control(self) -> HyperparameterForm:
            return self.form

    class Left(Message):
        """Escape in a field: the person wants the keyboard back for the view."""

    def __init__(self, hyperparameters: Settings | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._base = hyperparameters or QLearning.settings()
        self._between: set[str] = set()  # fields marked by a rule between fields
        self._rebuilding = False  # new fields are being built (see `load`)
        self.border_title = "Hyperparameters"
        self.border_subtitle = "↵ set · esc back"

    @property
    def fields(self) -> tuple[Field, ...]:
        """The fields shown: the schema of the settings last loaded."""
        return self._base.schema

    async def _rebuild(self) -> None:
        try:
            await self.recompose()
        finally:
            self._rebuilding = False

    def compose(self) -> ComposeResult:
        for field in self.fields:
            text = typed_text(getattr(self._base, field.name))
            box: Widget
            if isinstance(field, Param) and field.kind is not bool:  # typed in: a number
                box = TextField(text, id=f"hp-{field.name}", compact=True,
                                validators=[FieldValidator(field)], select_on_focus=True)
                hint = range_hint(field)
            else:  # picked from a few words
                words = ("true", "false") if isinstance(field, Param) else field.choices
                box = Select([(word, word) for word in words], value=text, allow_blank=False,
                             compact=True, id=f"hp-{field.name}")
                hint = ""
            box.tooltip = f"{field.help}: {field.expected()}"
            yield Horizontal(Label(field.title or field.name, classes="hp-label"), box,
                             Label(hint, classes="hp-hint"), classes="hp-row",
                             id=f"hp-row-{field.name}")
            yield Static("", id=f"hp-error-{field.name}", classes="hp-error", markup=False)

    # --- the fields --------------------------------------------------------
    def input(self, name: str) -> Input:
        """The Input of one typed hyperparameter, e.g. `input("learning_rate")`."""
        return self.query_one(f"#hp-{name}", Input)

    def control(self, name: str) -> Input | Select[str]:
        """The widget that edits one hyperparameter (an Input or a Select)."""
        return cast("Input | Select[str]", self.query_one(f"#hp-{name}"))

    def error(self, name: str) -> str:
        """The problem shown under a field ('' when none)."""
        widget = self.query_one(f"#hp-error-{name}", Static)
        return str(widget.content) if widget.has_class("-shown") else ""

    def is_invalid(self, name: str) -> bool:
        return self.control(name).has_class("-invalid")

    def _mark(self, name: str, problem: str | None) -> None:
        self.control(name).set_class(problem is not None, "-invalid")
        self.control(name).set_class(problem is None, "-valid")
        self.query_one(f"#hp-row-{name}").set_class(problem is not None, "-invalid")
        note = self.query_one(f"#hp-error-{name}", Static)
        if str(note.content) != (problem or ""):  # an update lays the screen out again
            note.update(problem or "")
        note.set_class(bool(problem), "-shown")

    @on(Input.Changed)
    def _changed(self, event: Input.Changed) -> None:
        event.stop()
        name = (event.input.id or "").removeprefix("hp-")
        result = event.validation_result
        problem = "; ".join(result.failure_descriptions if result else []) or None
        self._mark(name, problem)
        if problem is None and self._between:
            # any fix may settle a rule between fields; read() checks it again
            for other in self._between:
                if other != name:
                    self._mark(other, None)
            self._between.clear()

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.post_message(self.Submitted(self, self.read()))

    def action_leave(self) -> None:
        self.post_message(self.Left())

    @on(Select.Changed)
    def _picked(self, event: Select.Changed) -> None:
        event.stop()
        self._mark((event.select.id or "").removeprefix("hp-"), None)

    # --- reading and loading -----------------------------------------------
    def read(self) -> Settings | None:
        """The hyperparameters in the fields, or None with every problem marked."""
        if self._rebuilding:
            # Another algorithm's fields are on their way, holding what was loaded; the
            # old ones on screen meanwhile are not the settings' fields.
            return self._base
        values: dict[str, object] = {}
        ok = True
        fields = self.fields
        for field in fields:
            value = self.control(field.name).value
            text = value if isinstance(value, str) else ""
            problem = field_error(field, text) if isinstance(field, Param) else None
            self._mark(field.name, problem)
            if problem is None:
                values[field.name] = field.parse(text)
            else:
                ok = False
        if not ok:
            return None
        try:
            return self._base.replace(**values)
        except ValueError as exc:
            # A rule between fields (epsilon final above epsilon start): mark the
            # fields the message names, with the message in people's words.
            reason = str(exc)
            named = [f for f in fields if f.name in reason]
            for field in fields:
                reason = reason.replace(field.name, (field.title or field.name).lower())
            reason = reason[:1].upper() + reason[1:]
            marked = named or list(fields[:1])
            for field in marked:  # the reason once, under the last field it names
                self._mark(field.name, reason if field is marked[-1] else "")
                self._between.add(field.name)
            return None

    def load(self, hyperparameters: Settings) -> None:
        """Fill every field from `hyperparameters` and clear the marks; another
        algorithm's schema rebuilds the fields."""
        rebuild = hyperparameters.schema != self._base.schema
        self._base = hyperparameters
        self._between.clear()
        if rebuild or self._rebuilding or not self.children:
            # Built once the old fields are gone (ids repeat between schemas), or when
            # first composed (not yet: an app quit at once), from the values loaded last.
            if self.is_mounted and not self._rebuilding:
                self._rebuilding = True
                self.call_later(self._rebuild)
            return
        for field in self.fields:
            text = typed_text(getattr(hyperparameters, field.name))
            box = self.control(field.name)
            if box.value != text:
                box.value = text
            self._mark(field.name, None)

    @property
    def valid(self) -> bool:
        """True when no field is marked."""
        return not any(self.is_invalid(f.name) for f in self.fields)
