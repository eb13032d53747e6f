"""`restyle_on_focus`: a focus change restyles the focused widget alone.

Textual answers a widget's focus change by styling the widget and everything
below it afresh, its component classes (the colours a board draws with) too.
Where only the widget's own look follows the focus (a border, a tint), that is
most of a view switch's style work for nothing: this restyles the widget alone
and keeps its component styles, which no `:focus` rule of ours touches.
"""

from __future__ import annotations

from textual.widget import Widget


def restyle_on_focus(widget: Widget) -> None:
    """Apply the stylesheet to `widget` alone, keeping its component styles."""
    # The stylesheet asks the node for its component classes; none means "keep them".
    widget._get_component_classes = frozenset  # type: ignore[method-assign,assignment]
    try:
        widget.app.stylesheet.update_nodes([widget], animate=True)
    finally:
        del widget._get_component_classes


__all__ = ["restyle_on_focus"]
