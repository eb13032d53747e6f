"""The map editor's side of a view that shows it (the Train view, the Plan view)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tui_gym.core.mdp import NotAvailable
from tui_gym.ui.widgets.map_editor import MapEditor

if TYPE_CHECKING:
    from textual.app import App

    from tui_gym.games.maps import GridMap
    from tui_gym.session.session import Session

__all__ = ["apply_edit", "save_map", "show_optimum"]


def show_optimum(editor: MapEditor, session: Session, focus: Any) -> None:
    """Draw the session's map in `editor` with its exact optimum and how long it took."""
    game, kwargs = session.game, session.env_kwargs
    grid_map = game.grid_map(kwargs)
    started = time.perf_counter()
    solution = game.solution(kwargs)
    if isinstance(solution, NotAvailable):
        editor.show(grid_map, [], f"no exact optimum: {solution.reason}")
        return
    panels: list[Any] = []
    if solution.q is not None:
        panels = game.layout.heatmaps(solution.q, kwargs, focus, solution.marks)
    took = (time.perf_counter() - started) * 1000
    if "optimal_mean_steps" in solution.figures:
        figure = f"{solution.figures['optimal_mean_steps']:.3f} steps on average"
    else:
        figure = f"{solution.value:+.4f} return"
    editor.show(grid_map, panels, f"exact optimum {figure}, solved in {took:.0f} ms")


def apply_edit(app: App[Any], session: Session, event: MapEditor.Changed) -> bool:
    """Play the edited map (the app rebuilds the game); False, with the edit taken back in
    the editor, when it cannot be played."""
    event.editor.pending = max(0, event.editor.pending - 1)
    try:
        kwargs = session.game.with_map(session.env_kwargs, event.grid_map)
    except ValueError as error:
        app.notify(str(error), severity="warning", timeout=4)
        event.editor.drop_last(session.game.grid_map(session.env_kwargs))
        return False
    rebuild = getattr(app, "rebuild_map", None)
    if rebuild is None or not rebuild(kwargs, event.resized):
        event.editor.drop_last(session.game.grid_map(session.env_kwargs))
        return False
    return True


def save_map(app: App[Any], session: Session, grid_map: GridMap) -> None:
    """Write `grid_map` as `GAME-map.txt` in the current folder, and say where."""
    from tui_gym.games.maps import MapError
    from tui_gym.games.maps.files import write_map_file

    game = session.game
    path = Path.cwd() / f"{game.name}-map.txt"
    try:
        write_map_file(path, grid_map, f"{game.title} map, saved by tui-gym")
    except MapError as error:
        app.notify(str(error), severity="error")
        return
    app.notify(f"Map saved to {path} (play it with --map-file)", timeout=6)
