"""`FileScreen`: type the name of a file to save the agent to, or to load one from."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Input, Static

from tui_gym.ui.confirm_screen import ConfirmScreen
from tui_gym.ui.widgets.text_field import TextField

SUFFIX = ".tgym"


def resolve(text: str, must_exist: bool = False) -> Path:
    """The path a typed name stands for: `~` expanded, relative to the current folder,
    `.tgym` added when the name has no suffix and is not a folder (when loading, only
    if that file exists)."""
    path = Path(text.strip())
    with contextlib.suppress(RuntimeError):  # "~someone" with no such user: as written
        path = path.expanduser()
    plain = path.name and not path.suffix and not path.name.startswith(".")
    if plain and not path.is_dir():  # a folder's name stays as typed: it is refused later
        with_suffix = path.with_name(path.name + SUFFIX)
        if not must_exist or (with_suffix.exists() and not path.exists()):
            path = with_suffix
    return Path.cwd() / path if not path.is_absolute() else path


class FileScreen(ModalScreen[Path | None]):
    """Ask for a file name to save to (`saving`) or load from; dismisses with the path."""

    DEFAULT_CSS = """
    FileScreen { align: center middle; }
    FileScreen > Vertical {
        width: 72; max-width: 100%; height: auto; max-height: 100%;
        border: thick $primary; background: $surface; padding: 1 2;
    }
    FileScreen #file-title { text-style: bold; color: $accent; }
    FileScreen #file-name { margin-top: 1; }
    FileScreen #file-target { color: $text-muted; }
    FileScreen #file-error { color: $text-error; display: none; }
    FileScreen #file-error.-shown { display: block; }
    FileScreen #file-buttons { height: auto; margin-top: 1; align-horizontal: right; }
    FileScreen Button { margin-left: 2; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "dismiss", "Cancel", show=False)]

    def __init__(
        self, title: str, suggestion: str, perform: Callable[[Path], str | None], *, saving: bool,
    ) -> None:
        super().__init__()
        self.title_text = title
        self.suggestion = suggestion
        self.perform = perform
        self.saving = saving

    def compose(self) -> ComposeResult:
        verb = "Save" if self.saving else "Load"
        with Vertical():
            yield Static(self.title_text, id="file-title", markup=False)
            yield TextField(self.suggestion, placeholder="file name, e.g. my-agent.tgym",
                        id="file-name")
            yield Static("", id="file-target")
            yield Static("", id="file-error")
            with Horizontal(id="file-buttons"):
                yield Button(f"{verb} (enter)", id="file-go", variant="primary",
                             action="screen.go")
                yield Button("Cancel (esc)", id="file-cancel", action="screen.dismiss")

    def on_mount(self) -> None:
        self._show_target(self.suggestion)
        self.query_one(Input).focus()

    @property
    def error(self) -> str:
        """The error line as shown ("" when there is none)."""
        widget = self.query_one("#file-error", Static)
        return str(widget.render()) if widget.has_class("-shown") else ""

    def _say(self, error: str | None) -> None:
        widget = self.query_one("#file-error", Static)
        widget.update(Text(f"✗ {error}" if error else ""))
        widget.set_class(bool(error), "-shown")

    def _show_target(self, text: str) -> None:
        line = ""
        if text.strip():
            try:
                line = f"{'to' if self.saving else 'from'} {resolve(text, not self.saving)}"
            except (OSError, ValueError):
                line = ""
        self.query_one("#file-target", Static).update(Text(line))

    @on(Input.Changed, "#file-name")
    def _typed(self, event: Input.Changed) -> None:
        event.stop()
        self._say(None)
        self._show_target(event.value)

    @on(Input.Submitted, "#file-name")
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.action_go()

    def action_go(self) -> None:
        text = self.query_one(Input).value
        if not text.strip():
            self._say("Type a file name first.")
            return
        try:
            path = resolve(text, must_exist=not self.saving)
            folder, exists = path.is_dir(), path.exists()
            parent = path.parent.is_dir()
        except (OSError, ValueError) as exc:  # e.g. a NUL byte, a name too long
            self._say(f"{text.strip()!r} cannot be a file name ({exc}).")
            return
        if folder:
            self._say(f"{path} is a folder: add a file name.")
            return
        if self.saving and not parent:
            self._say(f"There is no folder {path.parent}.")
            return
        if self.saving and exists:
            self.app.push_screen(
                ConfirmScreen(
                    f"Replace {path.name}?",
                    f"{path} already exists. Saving replaces what it holds.", "Replace",
                ),
                lambda yes: self._replace(path, bool(yes)),
            )
            return
        self._finish(path)

    def _replace(self, path: Path, yes: bool) -> None:
        if yes:
            self._finish(path)
        else:
            self.query_one(Input).focus()

    def _finish(self, path: Path) -> None:
        error = self.perform(path)
        if error:
            self._say(error)
            self.query_one(Input).focus()
            return
        self.dismiss(path)
