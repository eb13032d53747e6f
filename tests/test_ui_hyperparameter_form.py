"""The hyperparameter form alone: read while another algorithm's fields are being built,
and loaded before its fields are."""

from __future__ import annotations

from textual.app import App, ComposeResult

from tui_gym.algorithms import algorithm
from tui_gym.ui.widgets.hyperparameter_form import HyperparameterForm


class FormApp(App[None]):
    def compose(self) -> ComposeResult:
        yield HyperparameterForm(algorithm("q-learning").settings())


async def test_reading_while_another_algorithms_fields_are_built_gives_what_was_loaded() -> None:
    app = FormApp()
    async with app.run_test(size=(60, 20)) as pilot:
        form = app.query_one(HyperparameterForm)
        for name in ("monte-carlo", "dyna-q", "q-learning"):
            settings = algorithm(name).settings()
            form.load(settings)
            assert form.read() == settings, name  # at once: the old fields are still there
            await pilot.pause()
            assert form.read() == settings, name  # and from the new fields
            assert {f.name for f in form.fields} == {f.name for f in settings.schema}


async def test_a_form_loaded_before_it_is_composed_shows_what_was_loaded() -> None:
    """An app quit within its first frame mounts the Train view while its form has not
    composed: loading it then raised (no fields yet); the fields come from what was
    loaded."""
    form = HyperparameterForm(algorithm("q-learning").settings())
    settings = algorithm("q-learning").settings().replace(learning_rate=0.25)
    form.load(settings)  # no fields yet
    app = App[None]()
    async with app.run_test(size=(60, 20)) as pilot:
        await app.mount(form)
        await pilot.pause()
        assert form.input("learning_rate").value == "0.25"
        assert form.read() == settings
