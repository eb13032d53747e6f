"""`TextBoard`: a game drawn as its own text picture, for envs with no board of their own."""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual.binding import Binding, BindingType

from tui_gym.ui.widgets.boards import NEW_EPISODE_HELP, NEW_EPISODE_KEYS, Board

ACTION_GROUP = Binding.Group("Act")


class TextBoard(Board):
    """Any game's text picture; digits take actions."""

    BORDER_TITLE = "Game"
    DEFAULT_CSS = """
    TextBoard > BoardCanvas { content-align: center middle; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        *(Binding(str(d), f"act('{d}')", f"action {d}", show=False, group=ACTION_GROUP)
          for d in range(10)),
        *NEW_EPISODE_KEYS,
    ]

    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("0-9", "take the action of that number"),
            *NEW_EPISODE_HELP,
        ]

    prompt = "Press an action's number; r starts over."
    over_hint = "This episode is over: press n, r or Enter for a new one."

    def action_next_episode(self) -> None:
        if self.episode_over:
            self.action_new_episode()

    def picture(self, width: int, height: int) -> Text:
        scene = self.scene
        text = str(scene.get("text") or "").rstrip("\n")
        if not text and scene.get("state") is not None:
            text = f"state {scene['state']}"
        lines = text.split("\n") if text else []
        actions = [str(a) for a in scene.get("actions", [])]
        if actions:
            lines += ["", "actions: " + "  ".join(actions[:10]) + "  (press the number)"]
        picture = Text("\n".join(line[:width] for line in lines[: max(1, height)]))
        picture.no_wrap = True
        return picture
