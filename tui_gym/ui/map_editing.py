"""The views' shared base `SessionView`, and the map editor's side of a view that shows it:
`MapEditingView` (the Train view, the Plan view), `show_optimum`."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from textual import on
from textual.containers import Vertical

from tui_gym.core.mdp import NotAvailable
from tui_gym.ui.widgets.map_editor import MapEditor

if TYPE_CHECKING:
    from tui_gym.session.session import Session

__all__ = ["MapEditingView", "SessionView", "show_optimum"]


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


class SessionView(Vertical):
    """A view of the app's session, filling the screen below the tabs; its body, a
    `VerticalScroll`, takes the height the rows above it leave. A row of `.controls`
    holds small buttons and a `.speed` label."""

    DEFAULT_CSS = """
    SessionView { height: 1fr; padding: 0 0 0 1; }
    SessionView > VerticalScroll { height: 1fr; scrollbar-size-vertical: 1; }
    SessionView .controls { height: 1; }
    SessionView .controls Button { min-width: 0; margin-right: 1; padding: 0; }
    SessionView .speed { width: auto; padding: 0 1; color: $text-accent; text-style: bold; }
    """

    @property
    def session(self) -> Session:
        return self.app.session  # type: ignore[attr-defined, no-any-return]

    def focus_default(self) -> None:
        """Give the keyboard to the view's own widget."""


class MapEditingView(SessionView):
    """A view that shows the map editor (`-mapping`) over the game it plays: each edit
    rebuilds the game through the app (`rebuild_map`), `s` saves the map, esc closes it.
    Its heatmaps sit in a `.heatmap-box`."""

    DEFAULT_CSS = """
    MapEditingView MapEditor { display: none; }
    MapEditingView.-mapping MapEditor { display: block; }
    MapEditingView .heatmap-box { height: auto; border: round $primary-background-lighten-2;
                                  border-title-color: $text-muted;
                                  border-subtitle-color: $text-disabled; }
    """

    focus_target: Any = None  # what the optimum's heatmap follows
    _editor_game = ""  # the game the editor's undo history belongs to

    @property
    def editor(self) -> MapEditor | None:
        """The editor, once it is there."""
        return self.query_one_optional(MapEditor)

    @property
    def editing_map(self) -> bool:
        return self.has_class("-mapping")

    def can_edit_map(self) -> bool:
        """Whether the game has a map to edit (else a notice says so)."""
        game = self.session.game
        if not game.editable:
            self.app.notify(f"{game.title} has no map to edit; the grid games do.",
                            severity="warning", timeout=4)
        return game.editable

    def start_editor(self) -> MapEditor:
        """Open the editor (mounted) on the session's map and draw its optimum."""
        editor = self.editor
        assert editor is not None
        game = self.session.game
        editor.start(game.grid_map(self.session.env_kwargs), game.map_tools)
        self._editor_game = game.name
        self.add_class("-mapping")
        self.show_editor()
        return editor

    def close_editor(self) -> None:
        self.remove_class("-mapping")
        self.focus_default()

    def follow_map(self) -> None:
        """After the session changed, an open editor closes on a game without a map, starts
        afresh on another game's, else draws the map as it is now."""
        editor, game = self.editor, self.session.game
        if not self.editing_map or editor is None:
            return
        if not game.editable:
            self.close_editor()
        elif editor.grid_map is None or self._editor_game != game.name:
            self.start_editor()
        else:
            self.show_editor()

    def show_editor(self) -> None:
        """Draw the session's map and its exact optimum in the editor."""
        if self.editor is not None:
            show_optimum(self.editor, self.session, self.focus_target)

    @on(MapEditor.Changed)
    def _map_changed(self, event: MapEditor.Changed) -> None:
        """Play the edited map; when it cannot be played, the edit is taken back."""
        event.stop()
        editor, session = event.editor, self.session
        editor.pending = max(0, editor.pending - 1)
        try:
            kwargs = session.game.with_map(session.env_kwargs, event.grid_map)
        except ValueError as error:
            self.app.notify(str(error), severity="warning", timeout=4)
            kwargs = None
        rebuild = getattr(self.app, "rebuild_map", None)
        if kwargs is None or rebuild is None or not rebuild(kwargs):
            editor.drop_last(session.game.grid_map(session.env_kwargs))
            self.show_editor()

    @on(MapEditor.SaveAsked)
    def _map_save(self, event: MapEditor.SaveAsked) -> None:
        """Write the map as `GAME-map.txt` in the current folder, and say where."""
        from tui_gym.games.maps import MapError
        from tui_gym.games.maps.files import write_map_file

        event.stop()
        game = self.session.game
        path = Path.cwd() / f"{game.name}-map.txt"
        try:
            write_map_file(path, event.grid_map, f"{game.title} map, saved by tui-gym")
        except MapError as error:
            self.app.notify(str(error), severity="error")
            return
        self.app.notify(f"Map saved to {path} (play it with --map-file)", timeout=6)

    @on(MapEditor.Closed)
    def _map_closed(self, event: MapEditor.Closed) -> None:
        event.stop()
        self.close_editor()
