"""Sutton & Barto's figures, run and checked: the registry behind `tui-gym book`."""

from __future__ import annotations

import importlib

from tui_gym.session.book.figure import BookFigure

__all__ = ["CHAPTERS", "BookFigure", "figure_named", "figures"]

# The modules of figures, each with its `FIGURES` (imported when first asked for).
CHAPTERS = ("dp", "td", "sweeps", "dyna")


def figures() -> list[BookFigure]:
    """Every figure, in the book's order (by chapter, and within one as listed)."""
    found = [figure for module in CHAPTERS
             for figure in importlib.import_module(f"{__name__}.{module}").FIGURES]
    return sorted(found, key=lambda f: int(f.name.split()[-1].split(".")[0]))


def figure_named(name: str) -> BookFigure:
    """The figure with this number or alias; `ValueError` naming the figures otherwise."""
    text = name.strip().lower().removeprefix("figure").strip()
    for figure in figures():
        if text == figure.name or text in figure.aliases:
            return figure
    names = ", ".join(f.name for f in figures())
    raise ValueError(f"no book figure {name!r}; the figures: {names}")
