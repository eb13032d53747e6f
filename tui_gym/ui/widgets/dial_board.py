"""`DialBoard`: a game whose move is a number picked from a range (a stake, cars to move)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from rich.text import Text
from textual.binding import Binding, BindingType

from tui_gym.ui.widgets.board_drawing import stack
from tui_gym.ui.widgets.boards import NEW_EPISODE_HELP, NEW_EPISODE_KEYS, Board
from tui_gym.ui.widgets.strip_widget import component_classes

DIAL_GROUP = Binding.Group("Dial")
BAR = 24  # gauge width at most


class DialBoard(Board):
    """Turn a dial to a number, then make the move."""

    DEFAULT_CSS = """
    DialBoard .dial--gauge { color: $accent; }
    DialBoard .dial--empty { color: $foreground 25%; }
    DialBoard .dial--pointer { color: $text; background: $accent; text-style: bold; }
    DialBoard .dial--muted { color: $text-muted; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    STYLE = "dial"
    BORDER_TITLE = "Game"

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("left,h", "turn(-1)", "−1", key_display="←", group=DIAL_GROUP),
        Binding("right,l", "turn(1)", "+1", key_display="→", group=DIAL_GROUP),
        Binding("down,j", "turn(-5)", "−5", key_display="↓", show=False),
        Binding("up,k", "turn(5)", "+5", key_display="↑", show=False),
        Binding("home", "turn(-1000)", "first", show=False),
        Binding("end", "turn(1000)", "last", show=False),
        Binding("enter,space", "take", "Go", key_display="enter"),
        NEW_EPISODE_KEYS[0],
    ]
    BUTTONS = (("◀", "turn(-1)"), ("Go [dim]enter[/]", "take"), ("▶", "turn(1)"),
               ("↺ New [dim]n[/]", "new_episode"))

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.pointer = 0
        self._fresh = True

    # --- the dial ----------------------------------------------------------
    @property
    def actions(self) -> list[str]:
        return [str(a) for a in self.scene.get("actions", [])]

    @property
    def allowed(self) -> int:
        names = self.actions
        return max(1, min(len(names), int(self.scene.get("allowed", len(names)) or 1)))

    def start_episode(self) -> None:
        self._fresh = True

    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        self.scene = dict(scene)
        if self._fresh and "start" in scene:
            self.pointer = int(scene["start"])
        self._fresh = False
        self.pointer = max(0, min(self.pointer, self.allowed - 1))
        self.border_title = str(scene.get("title") or "Game")
        super().show_scene(scene, reveal)

    def action_turn(self, by: int) -> None:
        if self.agent_playing:
            self.post_message(self.TakeOver())
            return
        self.pointer = max(0, min(self.allowed - 1, self.pointer + by))
        self.redraw()

    def action_take(self) -> None:
        if self.episode_over and not self.agent_playing:
            self.action_new_episode()
        elif self.actions:
            self.action_act(self.actions[self.pointer])

    def keys_for(self, action: str) -> list[str]:
        """The keys that make `action` from where the dial points now."""
        index = self.actions.index(action)
        steps = index - self.pointer
        return ["right" if steps > 0 else "left"] * abs(steps) + ["enter"]

    # --- what the board says ------------------------------------------------
    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("← / →", "turn the dial by one"), ("↓ / ↑", "turn the dial by five"),
            ("home / end", "the dial to either end"),
            ("enter / space", "make the move the dial points at (a new episode once over)"),
            NEW_EPISODE_HELP[0],
        ]

    @property
    def prompt(self) -> str:
        return str(self.scene.get("prompt") or "Turn the dial with ← →, then enter.")

    over_hint = "This episode is over: press n, r or Enter for a new one."

    def button_suggested(self, action: str) -> bool:
        return action == "new_episode" if self.episode_over else action == "take"

    # --- drawing --------------------------------------------------------------
    def picture(self, width: int, height: int) -> Text:
        scene = self.scene
        if not scene:
            return stack([Text("No episode yet.")], width, height)
        muted = self._style("muted")
        lines: list[Text] = []
        bars = [bar for bar in scene.get("bars", []) if len(bar) == 3]
        label_w = max((len(str(bar[0])) for bar in bars), default=0)
        unit = str(scene.get("unit", ""))
        for label, value, top in bars:
            room = max(4, min(BAR, width - label_w - 14))
            filled = round(room * float(value) / max(1.0, float(top)))
            line = Text(f"{str(label):<{label_w}}  ", style=muted)
            line.append("█" * filled, self._style("gauge"))
            line.append("░" * (room - filled), self._style("empty"))
            line.append(f"  {unit}{value:g}/{unit}{top:g}")
            lines.append(line)
        for said in scene.get("lines", []):
            lines.append(Text(str(said).format(who=self.player_name)[:width], style=muted))
        lines.append(Text(""))
        lines.append(self._dial(width))
        return stack(lines, width, height)

    def _dial(self, width: int) -> Text:
        """The actions around the pointer, the pointed one highlighted, as many as fit."""
        labels = self.scene.get("labels") or self.actions
        names = [str(label) for label in labels][: self.allowed]
        if not names:
            return Text("")
        cell = max(len(name) for name in names) + 2
        fit = max(1, (width - 4) // cell)
        first = max(0, min(self.pointer - fit // 2, len(names) - fit))
        shown = range(first, min(len(names), first + fit))
        muted, pointer = self._style("muted"), self._style("pointer")
        line = Text("◀ " if first > 0 else "  ", style=muted)
        for i in shown:
            line.append(names[i].center(cell), pointer if i == self.pointer else muted)
        line.append(" ▶" if shown.stop < len(names) else "  ", muted)
        return line
