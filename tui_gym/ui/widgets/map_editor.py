"""`MapEditor`: paint a grid game's map while the agent learns on it."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np
from textual import events
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import HorizontalScroll, Vertical
from textual.geometry import Region
from textual.message import Message
from textual.widget import Widget
from textual.widgets import Label

from tui_gym.core.heatmap import Heatmap
from tui_gym.games.maps import TOOLS, GridMap, Tool
from tui_gym.ui.widgets.heatmap_view import HeatmapView

__all__ = ["MapCanvas", "MapEditor"]

TILE_MARKS = {"S": "S", "R": "$"}  # tiles drawn with a letter beside the arrow
ICE = "~"
WIDE_MAP = 8  # columns, beyond which a cell shows its mark alone
HISTORY = 200  # edits undo remembers
VALUE_STEP = {"reward": 1.0, "slip": 0.1}


class MapCanvas(HeatmapView):
    """The editor's heatmap: the focus cell is the cursor, and a click paints."""

    @dataclass
    class Clicked(Message):
        """A click on a cell: paint it."""

        cell: tuple[int, int]

    def on_click(self, event: events.Click) -> None:
        cell = self.clicked_cell(event)
        if cell is not None:
            self.focus_cell = cell
            self.post_message(self.Clicked(cell))

    def cursor_region(self) -> Region | None:
        """Where the focus cell is drawn, in the canvas's content (None before it is)."""
        if self.focus_cell is None or not self._placements:
            return None
        place, (width, height) = self._placements[0], self._cell_geometry
        row, col = self.focus_cell
        return Region(place.x + col * width, place.y + row * height, width, height)


class MapEditor(Vertical):
    """The map, its exact optimum and a cursor; edits posted up as `Changed`."""

    DEFAULT_CSS = """
    MapEditor {
        height: auto;
        border: round $accent;
        border-title-color: $text-accent;
        border-subtitle-color: $text-muted;
    }
    MapEditor > Label { width: 100%; padding: 0 1; }
    MapEditor > HorizontalScroll { height: auto; scrollbar-size-horizontal: 1; }
    MapEditor MapCanvas { width: auto; min-width: 100%; }
    MapEditor #editor-tools { color: $text-muted; }
    MapEditor #editor-status.-unreachable { color: $text-warning; text-style: bold; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        *(Binding(str(i + 1), f"tool({i})", tool.name, show=False) for i, tool in enumerate(TOOLS)),
        Binding("enter", "paint", "Paint", show=False),
        Binding("left_square_bracket", "value(-1)", "Less", show=False, key_display="["),
        Binding("right_square_bracket", "value(1)", "More", show=False, key_display="]"),
        Binding("shift+right", "resize(0, 1)", "Wider", show=False),
        Binding("shift+left", "resize(0, -1)", "Narrower", show=False),
        Binding("shift+down", "resize(1, 0)", "Taller", show=False),
        Binding("shift+up", "resize(-1, 0)", "Shorter", show=False),
        Binding("u,ctrl+z", "travel('undo')", "Undo", key_display="u"),
        Binding("y,ctrl+y", "travel('redo')", "Redo", key_display="y"),
        Binding("s", "save", "Save map"),
        Binding("escape", "close", "Close editor", key_display="esc"),
    ]

    @dataclass
    class Changed(Message):
        """A new map: painted, resized, undone or redone."""

        editor: MapEditor
        grid_map: GridMap
        what: str  # the edit in words, e.g. "wall at row 1, col 2"

    @dataclass
    class SaveAsked(Message):
        """The person asked to save the map."""

        grid_map: GridMap

    class Closed(Message):
        """The person closed the editor."""

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:  # noqa: A002
        super().__init__(id=id, classes=classes)
        self.grid_map: GridMap | None = None
        self.tools: tuple[Tool, ...] = TOOLS
        self.tool: Tool = TOOLS[1]
        # None: the game's own reward for the tile (a hole costs what the game says).
        self.values: dict[str, float | None] = {t.name: t.default for t in TOOLS}
        self.undo_stack: list[GridMap] = []
        self.redo_stack: list[GridMap] = []
        self.last_edit = ""
        self._optimum_text = ""
        self._axes: tuple[tuple[str, ...], tuple[str, ...]] = ((), ())  # the canvas's labels
        self.pending = 0  # edits posted that the owner has not taken yet

    def compose(self) -> ComposeResult:
        yield Label("", id="editor-tools")
        with HorizontalScroll():  # a map wider than the editor scrolls with the cursor
            yield MapCanvas(id="editor-canvas")
        yield Label("", id="editor-status")

    def on_mount(self) -> None:
        self.border_title = "Map editor"
        self.border_subtitle = "esc closes"
        self.canvas.focus_cell = (0, 0)

    @property
    def canvas(self) -> MapCanvas:
        return self.query_one(MapCanvas)

    @property
    def cursor(self) -> tuple[int, int]:
        return self.canvas.focus_cell or (0, 0)

    # --- data in -------------------------------------------------------------------
    def start(self, grid_map: GridMap, tool_names: tuple[str, ...]) -> None:
        """Edit `grid_map` afresh (forgetting undo) with these tools."""
        self.undo_stack.clear()
        self.redo_stack.clear()
        self.pending = 0
        self.tools = tuple(t for t in TOOLS if t.name in tool_names)
        if self.tool not in self.tools:
            self.tool = next((t for t in self.tools if t.name == "wall"), self.tools[0])
        self.grid_map = grid_map
        self.last_edit = ""

    def show(self, grid_map: GridMap, panels: list[Heatmap], optimum: str) -> None:
        """Draw the map and its solved optimum (`panels` from the game's layout); while
        edits are on their way the editor keeps its own, newer map."""
        if not self.pending:
            self.grid_map = grid_map
        canvas = self.canvas
        self._axes = ((), ())
        if panels:
            canvas.show([self._dress(panels[0], grid_map)])
            if panels[0].shape == (grid_map.rows, grid_map.cols):
                self._axes = (panels[0].row_labels, panels[0].col_labels)
        else:
            canvas.show_message("No exact optimum to show for this map.")
        r, c = self.cursor
        canvas.focus_cell = (min(r, grid_map.rows - 1), min(c, grid_map.cols - 1))
        self._optimum_text = optimum
        self._show_tools()
        self._show_status()
        self.call_after_refresh(self.cursor_in_sight)

    def _dress(self, panel: Heatmap, grid_map: GridMap) -> Heatmap:
        """The optimum's panel with the start, reward cells and ice marked."""
        if panel.shape != (grid_map.rows, grid_map.cols):
            return panel
        slip = grid_map.slip_table()
        # A wide map keeps one character a cell (the mark instead of the arrow), so that
        # twelve columns fit beside the side panel at 80 columns.
        wide = grid_map.cols > WIDE_MAP

        def dressed(cell: tuple[int, int], label: str) -> str:
            mark = TILE_MARKS.get(grid_map.tile(cell), "")
            ice = ICE if slip.get(cell, 0.0) > 0 else ""
            return (mark or ice or label) if wide else mark + label + ice

        labels = tuple(tuple(dressed((r, c), label) for c, label in enumerate(line))
                       for r, line in enumerate(panel.labels))
        present = [word for mark, word, here in (
            ("S", "start", grid_map.start is not None),
            ("$", "reward cell", "R" in grid_map.tiles()), (ICE, "ice", bool(slip)),
        ) if here for word in [f"{mark} {word}"]]
        legend = "  ".join(present) + "  " + panel.legend.replace(
            "* not an optimal move", "").replace("  * off every shortest path", "")
        # Every arrow here is an optimal move: nothing to mark.
        return replace(panel, title="the exact optimum: value and optimal move",
                       labels=labels, legend=legend.strip(),
                       marked=np.zeros(panel.shape, dtype=bool))

    def _show_tools(self) -> None:
        parts = []
        for i, tool in enumerate(TOOLS):
            if tool not in self.tools:
                continue
            name = tool.name
            value = self.values[tool.name]
            if tool.value and value is not None:
                name += f" {value:+g}" if tool.value == "reward" else f" {value:g}"
            text = f"{i + 1} {name}"
            parts.append(f"[reverse]{text}[/]" if tool is self.tool else text)
        keys = "enter paint  [ ] value  shift+←→↑↓ size  u undo  y redo  s save"
        self.query_one("#editor-tools", Label).update("  ".join(parts) + "\n" + keys)

    def _show_status(self) -> None:
        grid_map = self.grid_map
        if grid_map is None:
            return
        status = self.query_one("#editor-status", Label)
        cursor = self.cursor
        cell = f"{self.where(cursor)}: {grid_map.describe(cursor)}" if grid_map.inside(
            cursor) else ""
        # A map with no start (a target anywhere): every free cell reaches every other.
        free = grid_map.start is None
        reachable = grid_map.free_connected() if free else grid_map.goal_reachable()
        warning = "" if reachable else "  ⚠ no goal can be reached on this map"
        status.set_class(not reachable, "-unreachable")
        done = f"  · {self.last_edit}" if self.last_edit else ""
        status.update(f"{grid_map.size_text} · {cell}{done}\n{self._optimum_text}{warning}")

    def where(self, cell: tuple[int, int]) -> str:
        """'row 1, col 2': a cell as the map's axes label it (a game may number its rows
        from the bottom up, as GridWorld does)."""
        rows, cols = self._axes
        row, col = cell
        row_label = rows[row] if row < len(rows) else str(row)
        col_label = cols[col] if col < len(cols) else str(col)
        return f"row {row_label}, col {col_label}"

    # --- edits ---------------------------------------------------------------------
    def _apply(self, new: GridMap, what: str) -> None:
        old = self.grid_map
        if old is None or new == old:
            return
        self.undo_stack.append(old)
        del self.undo_stack[:-HISTORY]
        self.redo_stack.clear()
        self._post(new, what)

    def _post(self, new: GridMap, what: str) -> None:
        # The map is the new one at once: keys that come before the owner has rebuilt
        # the game edit this map, not the one before.
        self.grid_map = new
        self.pending += 1
        self.last_edit = what
        self.post_message(self.Changed(self, new, what))

    def paint(self, cell: tuple[int, int]) -> None:
        """Paint `cell` with the current tool (a message says why when it cannot)."""
        if self.grid_map is None:
            return
        tool = self.tool
        value = self.values[tool.name] if tool.value else None
        try:
            new = self.grid_map.painted(cell, tool, value)
        except ValueError as error:
            self.app.notify(str(error), severity="warning", timeout=3)
            return
        self._apply(new, f"{tool.name} at {self.where(cell)}")

    def drop_last(self, shown: GridMap) -> None:
        """Forget the last edit posted: the owner could not apply it and plays `shown`."""
        if self.last_edit not in ("undone", "redone") and self.undo_stack:
            self.undo_stack.pop()
        self.grid_map = shown
        self.last_edit = ""

    def action_tool(self, index: int) -> None:
        tool = TOOLS[index]
        if tool not in self.tools:
            self.app.notify(f"This game's map takes {', '.join(t.name for t in self.tools)}.",
                            severity="warning", timeout=3)
            return
        self.tool = tool
        self._show_tools()
        self.paint(self.cursor)

    def action_paint(self) -> None:
        self.paint(self.cursor)

    def action_value(self, direction: int) -> None:
        tool = self.tool
        if not tool.value:
            return
        value = (self.values[tool.name] or 0.0) + direction * VALUE_STEP[tool.value]
        if tool.value == "slip":
            value = min(1.0, max(0.0, round(value, 2)))
        self.values[tool.name] = round(value, 6)
        self._show_tools()

    def action_resize(self, d_rows: int, d_cols: int) -> None:
        grid_map = self.grid_map
        if grid_map is None:
            return
        rows, cols = grid_map.rows + d_rows, grid_map.cols + d_cols
        if "start" not in {t.name for t in self.tools}:
            rows = cols = grid_map.rows + d_rows + d_cols  # a square grid stays square
        try:
            new = grid_map.resized(rows, cols)
        except ValueError as error:
            self.app.notify(str(error), severity="warning", timeout=3)
            return
        self._apply(new, f"resized to {new.size_text}")

    def action_travel(self, what: str) -> None:
        """Undo or redo: the map from one stack, the one shown onto the other."""
        stacks = (self.undo_stack, self.redo_stack)
        back, forth = stacks if what == "undo" else stacks[::-1]
        if not back or self.grid_map is None:
            self.last_edit = f"nothing to {what}"
            self._show_status()
            self.app.notify(f"Nothing to {what}.", timeout=2)
            return
        forth.append(self.grid_map)
        self._post(back.pop(), f"{what}ne")  # "undone", "redone"

    def action_save(self) -> None:
        if self.grid_map is not None:
            self.post_message(self.SaveAsked(self.grid_map))

    def action_close(self) -> None:
        self.post_message(self.Closed())

    # --- from the canvas -----------------------------------------------------------
    def on_map_canvas_clicked(self, event: MapCanvas.Clicked) -> None:
        event.stop()
        self.paint(event.cell)

    def on_heatmap_view_focus_changed(self, event: HeatmapView.FocusChanged) -> None:
        event.stop()  # the cursor moved: the train view's own heatmap must not follow
        self._show_status()
        self.cursor_in_sight()

    def cursor_in_sight(self) -> None:
        """Scroll the boxes around the map, this one's and the view's, until the cursor's
        cell shows (as Textual's `scroll_to_widget` does for a widget)."""
        canvas = self.canvas
        region = canvas.cursor_region()
        if region is None:
            return
        region = region.translate(canvas.virtual_region.offset + canvas.styles.gutter.top_left)
        widget: Widget = canvas
        while isinstance(widget.parent, Widget) and region:
            box = widget.parent
            scrolled = box.scroll_to_region(region, animate=False, immediate=True)
            region = region.translate(
                box.virtual_region.offset + box.styles.border.spacing.top_left - scrolled)
            widget = box

    def focus_canvas(self) -> None:
        self.canvas.focus()
