"""`TaxiBoard`: Taxi's city: walls, four coloured stands, the passenger, the destination, the cab.

Scene keys: "taxi", "passenger" (a stand, or `len(stands)` aboard), "destination",
"stands", "stand_names", "walls" (east side of each cell), "rows", "cols",
"last_action", "last_illegal", "rainy".
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from rich.style import Style
from rich.text import Text
from textual.binding import Binding, BindingType
from textual.geometry import Offset

from tui_gym.ui.widgets.board_drawing import (
    Cell,
    CharGrid,
    MapBoard,
    MapShape,
    cell_of,
    legend,
    listed,
    on_tile,
    read_as,
    shape_fits,
)
from tui_gym.ui.widgets.boards import NEW_EPISODE_HELP, NEW_EPISODE_KEYS, arrow_bindings
from tui_gym.ui.widgets.numbers import fit
from tui_gym.ui.widgets.strip_widget import component_classes

MOVES: dict[str, Cell] = {"south": (1, 0), "north": (-1, 0), "east": (0, 1), "west": (0, -1)}
MOVE_OF: dict[Cell, str] = {step: name for name, step in MOVES.items()}
STAND_NAMES = ("R", "G", "Y", "B")
STAND_COLOURS = 4  # component classes taxi--stand-0 .. -3, used in turn
PASSENGER, DESTINATION = "☺", "◎"

# What an action did: its words (longest first), their style, and whether the line goes
# on to say where the passenger is going.
Event = tuple[tuple[str, ...], str, bool]


TAXI_SIZES = (
    (11, 4), (9, 4), (11, 3), (9, 3), (7, 3), (9, 2), (7, 2), (5, 2), (9, 1), (7, 1), (5, 1),
    (3, 1),
)


def choose_shape(rows: int, cols: int, width: int, height: int) -> MapShape:
    """The largest drawing of the city that fits with its wall all round, else the largest
    without it (the smallest one if none does): the city's edge is a wall too."""
    shapes = [MapShape(rows, cols, cell_w, cell_h, gap=1, frame=frame)
              for frame in (True, False) for cell_w, cell_h in TAXI_SIZES]
    return next((shape for shape in shapes if shape_fits(shape, width, height)), shapes[-1])


class TaxiBoard(MapBoard):
    """Taxi: drive to the passenger ☺, pick them up, drop them off at ◎."""

    STYLE = "taxi"
    EMPTY = "No city yet."

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    TaxiBoard .taxi--road { background: #3a3d42; color: #8b9099; }
    TaxiBoard .taxi--road-alt { background: #34373c; color: #8b9099; }
    TaxiBoard .taxi--lane { background: #3a3d42; color: #6f747c; }
    TaxiBoard .taxi--wall { background: #3a3d42; color: #f0f0f0; text-style: bold; }
    TaxiBoard .taxi--rain { color: #56687c; }
    TaxiBoard .taxi--stand-0 { background: #8f2f2f; color: #ffd6d6; text-style: bold; }
    TaxiBoard .taxi--stand-1 { background: #2f7a3f; color: #d6ffdf; text-style: bold; }
    TaxiBoard .taxi--stand-2 { background: #8a7520; color: #fff4c9; text-style: bold; }
    TaxiBoard .taxi--stand-3 { background: #2f548f; color: #d6e6ff; text-style: bold; }
    TaxiBoard .taxi--passenger { color: #ffffff; text-style: bold; }
    TaxiBoard .taxi--destination { color: #ffffff; text-style: bold; }
    TaxiBoard .taxi--cab { background: #f5c518; color: #1b1b1b; text-style: bold; }
    TaxiBoard .taxi--cab-full { background: #37c46b; color: #0b2414; text-style: bold; }
    TaxiBoard .taxi--caption { color: $text-muted; }
    TaxiBoard .taxi--note { color: $text-warning; text-style: bold; }
    TaxiBoard .taxi--good { color: $text-success; text-style: bold; }
    TaxiBoard .taxi--bad { color: $text-error; text-style: bold; }
    """
    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    BINDINGS: ClassVar[list[BindingType]] = [
        *arrow_bindings("north", "south", "west", "east", "Drive"),
        Binding("k", "act('pickup')", "Pick up", tooltip="Pick the passenger up"),
        Binding("l,o", "act('dropoff')", "Drop off", key_display="l", tooltip="Drop them off"),
        *NEW_EPISODE_KEYS,
    ]

    BUTTONS = (
        ("Pick up [dim]k[/]", "act('pickup')"), ("Drop off [dim]l[/]", "act('dropoff')"),
        ("↺ New [dim]n[/]", "new_episode"),
    )

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._read({})

    # --- what the board says ---------------------------------------------------
    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("↑ ↓ ← →  or  w a s d", "drive north, south, west, east"),
            ("k", "pick the passenger up"), ("l / o", "drop the passenger off"),
            *NEW_EPISODE_HELP,
            ("click a cell", "drive one cell towards it; click the cab to pick up or drop off"),
        ]

    prompt = "Drive with the arrows or WASD; k picks up, l drops off."
    over_hint = "This ride is over: press n, r or Enter (or click New) for another."

    def button_enabled(self, action: str) -> bool:
        return action == "new_episode" or not self.episode_over

    def button_suggested(self, action: str) -> bool:
        return self.episode_over and action == "new_episode"

    @property
    def aboard(self) -> bool:
        """Whether the passenger is in the cab."""
        return self.passenger is not None and self.passenger >= len(self.stands) > 0

    # --- the scene -----------------------------------------------------------------
    def show_scene(self, scene: Mapping[str, Any], reveal: bool = True) -> None:
        previous = (None, None) if self._fresh else (self.taxi, self.destination)
        self._read(scene)
        action = scene.get("last_action")
        self._event = self._event_of(*previous, None if action is None else str(action),
                                     bool(scene.get("last_illegal")))
        self._fresh = False
        super().show_scene(scene, reveal)

    def _read(self, scene: Mapping[str, Any]) -> None:
        """The city and who is where, from a scene."""
        self.rows = read_as(int, scene.get("rows")) or 5
        self.cols = read_as(int, scene.get("cols")) or 5
        self.taxi = cell_of(scene.get("taxi"))
        self.stands = [cell for item in listed(scene.get("stands")) if (cell := cell_of(item))]
        self.stand_names = [str(name) for name in scene.get("stand_names") or STAND_NAMES]
        self.passenger = read_as(int, scene.get("passenger"))
        self.destination = read_as(int, scene.get("destination"))
        self.walls = frozenset(cell for item in listed(scene.get("walls"))
                               if (cell := cell_of(item)))
        self.rainy = bool(scene.get("rainy"))
        self.border_title = "Taxi · rain" if self.rainy else "Taxi"

    def stand_name(self, index: int | None) -> str:
        if index is None or not 0 <= index < len(self.stands):
            return "?"
        return self.stand_names[index] if index < len(self.stand_names) else str(index)

    def blocked(self, cell: Cell, move: str) -> bool:
        """Whether a wall or the city's edge stops a move from `cell`."""
        d_col = MOVES[move][1]  # a wall stands on the east side of its cell
        wall = cell if d_col == 1 else (cell[0], cell[1] - 1) if d_col == -1 else None
        return self._off_edge(cell, move) or wall in self.walls

    def _event_of(
        self, previous: Cell | None, previous_destination: int | None, action: str | None,
        illegal: bool,
    ) -> Event | None:
        """What the last action did, in words from longest to shortest, and their style."""
        taxi, to = self.taxi, self.stand_name(self.destination)
        if taxi is None or action is None or previous is None:
            return None
        if (
            previous_destination is not None
            and self.destination != previous_destination
            and self.aboard
        ):
            return (f"The passenger changed their mind: now to {to}", f"Now to {to}"), "note", False
        if action == "pickup":
            if illegal:
                why = "already aboard" if self.aboard else "the passenger is not here"
                return (f"Illegal pickup (−10): {why}", "Illegal pickup (−10)"), "bad", True
            return (f"Picked the passenger up: now to {to}", f"Picked up: to {to}"), "good", False
        if action == "dropoff":
            if illegal:
                why = "drop off at a stand" if self.aboard else "no passenger aboard"
                return (f"Illegal drop-off (−10): {why}", "Illegal drop-off (−10)"), "bad", True
            if self.passenger == self.destination:
                return (f"Passenger delivered to {to}!", f"Delivered to {to}!"), "good", False
            at = self.stand_name(self.passenger)
            return (f"Dropped the passenger at {at}, not {to}", f"Dropped at {at}"), "note", True
        if action not in MOVES:
            return None
        went = MOVE_OF.get((taxi[0] - previous[0], taxi[1] - previous[1]))
        if self.rainy and went != action and not (went is None and self.blocked(previous, action)):
            outcome = f"went {went}" if went else "stayed put"
            rain = (
                f"The rain pushed the cab: asked {action}, {outcome}",
                f"Rain: asked {action}, {outcome}", f"Rain: {outcome}",
            )
            return rain, "note", True
        if went is None:
            blocker = "the edge of the city" if self._off_edge(previous, action) else "a wall"
            return (f"{blocker.capitalize()} blocks the way {action}", "Blocked"), "caption", True
        return (f"Drove {action}", f"Drove {action}"), "caption", True

    def _off_edge(self, cell: Cell, move: str) -> bool:
        d_row, d_col = MOVES[move]
        return not (0 <= cell[0] + d_row < self.rows and 0 <= cell[1] + d_col < self.cols)

    # --- drawing -----------------------------------------------------------------
    def map_size(self) -> tuple[int, int] | None:
        if self.taxi is None or self.rows <= 0 or self.cols <= 0:
            return None
        return self.rows, self.cols

    choose_shape = staticmethod(choose_shape)

    def _cab(self, width: int) -> tuple[str, Style]:
        """The cab's text (at most `width` characters) and style: full or empty."""
        text = ("TAXI" if width >= 9 else "T") + (PASSENGER if self.aboard else "")
        return text, self._style("cab-full" if self.aboard else "cab")

    def _status(self) -> tuple[str, ...]:
        """Where the passenger is and is going, longest words first."""
        to = self.stand_name(self.destination)
        if self.aboard:
            return f"Passenger aboard, going to {to}", f"{PASSENGER} aboard → {to}"
        if self.passenger is not None and self.passenger == self.destination:
            return f"Passenger delivered at {to}", f"Delivered at {to}"
        at = self.stand_name(self.passenger)
        return f"Passenger waiting at {at}, going to {to}", f"{PASSENGER} at {at} → {to}"

    def _paint_tile(self, grid: CharGrid, cell: Cell, shape: MapShape) -> None:
        w, h = shape.cell_w, shape.cell_h
        x0, y0 = shape.x_of(cell[1]), shape.y_of(cell[0])
        mid = h // 2
        stand = self.stands.index(cell) if cell in self.stands else None
        if stand is None:
            tile = self._style("road-alt" if (cell[0] + cell[1]) % 2 else "road")
            grid.fill(x0, y0, w, h, " ", tile)
            if self.rainy and h >= 2:
                rain = on_tile(self._style("rain"), tile)
                for line in range(h):
                    for x in range(w):
                        if (x + 3 * line + cell[0] + 3 * cell[1]) % 7 == 0:
                            grid.put(x0 + x, y0 + line, "╱", rain)
        else:
            tile = self._style(f"stand-{stand % STAND_COLOURS}")
            grid.fill(x0, y0, w, h, " ", tile)
            grid.put(x0, y0, self.stand_name(stand)[: max(1, w // 3)], tile)
            if stand == self.destination:
                grid.put(x0 + w - 1, y0, DESTINATION, on_tile(self._style("destination"), tile))
        cab_here = cell == self.taxi
        cab_text, cab_style = self._cab(w)
        chip_w = len(cab_text) + (2 if w >= len(cab_text) + 4 else 0)
        chip_x = x0 + (w - chip_w) // 2
        if stand is not None and self.passenger == stand and not self.aboard:  # or just delivered
            person = on_tile(self._style("passenger"), tile)
            x = chip_x - 1 if cab_here else x0 + w // 2
            grid.put(max(x0, x), y0 + mid, PASSENGER, person)
        if cab_here:
            if w >= 7 and h >= 3:
                under = grid.styles[y0 + mid - 1][chip_x]
                grid.pill(chip_x, y0 + mid - 1, chip_w, 3, cab_style, under)
            grid.put(chip_x, y0 + mid, cab_text.center(chip_w), cab_style)

    def draw_map(self, shape: MapShape, width: int, spare: int) -> list[Text]:
        grid = CharGrid(shape.width, shape.height, self._style("lane"))
        lane, wall = self._style("lane"), self._style("wall")
        for row in range(shape.rows):
            for col in range(shape.cols):
                self._paint_tile(grid, (row, col), shape)
            for col in range(shape.cols - 1):
                x = shape.x_of(col) + shape.cell_w
                mark = ("┃", wall) if (row, col) in self.walls else ("┆", lane)
                grid.fill(x, shape.y_of(row), 1, shape.cell_h, *mark)
        if shape.frame:
            last = shape.height - 1
            grid.fill(0, 1, 1, last - 1, "┃", wall)
            grid.fill(shape.width - 1, 1, 1, last - 1, "┃", wall)
            grid.put(0, 0, "┏" + "━" * (shape.width - 2) + "┓", wall)
            grid.put(0, last, "┗" + "━" * (shape.width - 2) + "┛", wall)
            for col in range(shape.cols - 1):
                x = shape.x_of(col) + shape.cell_w
                if (0, col) in self.walls:
                    grid.put(x, 0, "┳", wall)
                if (shape.rows - 1, col) in self.walls:
                    grid.put(x, last, "┻", wall)
        return grid.lines()

    def caption(self, width: int) -> Text:
        """What the last action did and, when it fits, where the passenger is going."""
        status = self._status()
        label = self._style("caption")
        if self._event is None:
            return Text(fit(status, width), label)
        texts, style, then_status = self._event
        if then_status:  # the longest words that leave room for where the passenger goes
            for text in texts:
                where = [place for place in status if len(text) + 3 + len(place) <= width]
                if where:
                    return Text.assemble(
                        (text, self._style(style)), (" · ", label), (where[0], label)
                    )
        return Text(fit(texts, width), self._style(style))

    def legend(self, width: int) -> Text | None:
        """'T taxi  ☺ passenger  ◎ destination  ┃ wall' (None if too wide)."""
        cab_text, cab_style = self._cab(3)
        road = self._style("road")  # the marks as on the map, so they show on any theme
        items = [
            (cab_text, cab_style, "taxi"),
            (PASSENGER, on_tile(self._style("passenger"), road), "passenger"),
            (DESTINATION, on_tile(self._style("destination"), road), "destination"),
            ("┃", self._style("wall"), "wall"),
        ]
        return legend(items, self._style("caption"), width)

    # --- keys and clicks -----------------------------------------------------------
    def canvas_clicked(self, offset: Offset) -> None:
        """Drive one cell towards the clicked cell; a click on the cab picks up or drops off."""
        if self.layout_drawn is None or self.taxi is None:
            return
        cell = self.layout_drawn.cell_at(offset)
        if cell is None:
            return
        if cell == self.taxi:
            self.action_act("dropoff" if self.aboard else "pickup")
        else:
            self.step_to(self.taxi, cell, MOVE_OF)


__all__ = ["MOVES", "TaxiBoard", "choose_shape"]
