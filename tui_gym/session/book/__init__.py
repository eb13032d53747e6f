"""Sutton & Barto's figures, run and checked: the registry behind `tui-gym book`."""

from __future__ import annotations

import importlib

from tui_gym.session.book.figure import BookFigure

__all__ = ["FIGURE_MODULES", "BookFigure", "figure_named", "figures"]

# One module a figure (in the book's order).
FIGURE_MODULES = (
    "fig_3_2", "fig_3_5", "fig_4_1", "fig_4_2", "fig_4_3", "fig_6_2", "fig_6_3", "fig_6_4",
    "fig_6_5", "fig_6_6", "fig_7_2", "fig_8_2", "fig_8_4", "fig_8_5", "example_8_4", "fig_12_3",
    "fig_12_6",
)


def figures() -> list[BookFigure]:
    """Every figure, in the book's order (by chapter, and within one as listed)."""
    found = [importlib.import_module(f"{__name__}.{module}").FIGURE for module in FIGURE_MODULES]
    return sorted(found, key=lambda f: int(f.name.split()[-1].split(".")[0]))


def figure_named(name: str) -> BookFigure:
    """The figure with this number or alias; `ValueError` naming the figures otherwise."""
    text = name.strip().lower().removeprefix("figure").strip()
    for figure in figures():
        if text == figure.name or text in figure.aliases:
            return figure
    names = ", ".join(f.name for f in figures())
    raise ValueError(f"no book figure {name!r}; the figures: {names}")
