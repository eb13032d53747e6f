"""Bring your own env: any registered Gymnasium env with a transition table."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import NotAvailable
from tui_gym.core.wrappers import build_env
from tui_gym.games.base import TIED, HeatmapLayout, ansi_text
from tui_gym.games.model import DiscreteStates, ModelGame, table_model

__all__ = ["PAGE", "GenericGame", "check_fit"]

PAGE = 25  # states a heatmap page shows


def check_fit(env_id: str) -> NotAvailable | None:
    """None when `env_id` can be played as a generic game, else what it lacks."""
    model = table_model(env_id)
    if not isinstance(model, NotAvailable):
        return None
    if " could not be built: " in model.reason:
        return model
    return NotAvailable(
        f"{env_id} does not fit: {model.reason.split(': ', 1)[-1]} (tui-gym plays envs with "
        "Discrete observations and actions and a transition table P)"
    )


class GenericStates(DiscreteStates):
    """The env's `Discrete` states; its text render as the board."""

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        text = ansi_text(game_env) if getattr(game_env, "render_mode", None) == "ansi" else ""
        state = getattr(game_env, "s", None)
        return {"text": text, "state": None if state is None else int(state),
                "actions": list(self.game.action_names)}


class TableLayout(HeatmapLayout):
    """A state x action table; past `PAGE` states, pages picked on a first panel."""

    focus_help = "choose a page of states"

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        values = np.asarray(q, dtype=float)
        if values.ndim != 2 or 0 in values.shape:
            return []
        n_states, n_actions = values.shape
        greedy = values.argmax(axis=1)
        tied = (values == values[:, :1]).all(axis=1)
        wrong = np.zeros(n_states, dtype=bool)
        if isinstance(marks, np.ndarray) and marks.shape == values.shape:
            wrong = ~marks[np.arange(n_states), greedy] & ~tied
        pages = -(-n_states // PAGE)
        page = 0 if focus is None else min(max(0, int(focus)), pages - 1)
        rows = range(page * PAGE, min(n_states, (page + 1) * PAGE))
        labels = tuple(
            tuple(("●" if a == greedy[s] and not tied[s] else TIED if tied[s] else "")
                  for a in range(n_actions))
            for s in rows
        )
        marked = np.zeros((len(rows), n_actions), dtype=bool)
        marked[np.arange(len(rows)), greedy[rows.start:rows.stop]] = wrong[rows.start:rows.stop]
        table = Heatmap(
            title=f"Q, states {rows.start}-{rows.stop - 1}", row_labels=tuple(str(s) for s in rows),
            col_labels=tuple(self.game.action_names), values=values[rows.start:rows.stop].copy(),
            labels=labels, marked=marked,
            legend=f"rows: states  cols: actions  ● greedy  {TIED} tie  * not optimal",
        )
        if pages == 1:
            return [table]
        starts = np.arange(pages) * PAGE
        picker = Heatmap(
            title="pages",
            row_labels=("from",),
            col_labels=tuple(str(s) for s in starts),
            values=np.array([[values[s:s + PAGE].max(axis=1).mean() for s in starts]]),
            labels=(tuple(f"{int(wrong[s:s + PAGE].sum())}*" if wrong[s:s + PAGE].any() else ""
                          for s in starts),),
            marked=np.zeros((1, pages), dtype=bool),
            legend="pages: mean max Q, n* states not optimal",
        )
        return [picker, table]

    def default_focus(self, kwargs: Mapping[str, Any]) -> Any:
        return 0

    def focus_at(self, row: int, col: int, kwargs: Mapping[str, Any]) -> Any:
        return max(0, col)

    def focus_cell(self, focus: Any, kwargs: Mapping[str, Any]) -> tuple[int, int] | None:
        return (0, int(focus or 0))


class GenericGame(ModelGame):
    """An env of the caller's choosing, played from its transition table."""

    def __init__(self, env_id: str) -> None:
        super().__init__()
        self.env_id = env_id
        self.name = env_id.lower()
        self.title = env_id.split(":")[-1]
        self.description = f"{self.title}: played from its own transition table"
        env: Any = build_env(env_id)
        try:
            self.action_names = tuple(str(a) for a in range(int(env.action_space.n)))
            modes = env.metadata.get("render_modes", []) or []
            self.render_mode = "ansi" if "ansi" in modes else None
        finally:
            env.close()
        self.states = GenericStates(self)
        self.layout = TableLayout(self)
        model = self.base_model({})
        self.layout.has_focus = not isinstance(model, NotAvailable) and model.n_states > PAGE
