"""The step-by-step panel: how the learner used the transition just taken."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from rich.text import Text
from textual.widgets import Static

from tui_gym.algorithms import UpdateRecord
from tui_gym.games.words import plural
from tui_gym.ui.widgets.strip_widget import panel_css

__all__ = ["StepPanel", "explain"]

EPISODE_UPDATES_SHOWN = 4  # Monte Carlo: the first few of an episode's updates


def _num(value: float) -> str:
    """'+0.5', '−1' (a true minus, as the operators around it), '0'."""
    return f"{value:+.4g}".replace("-", "−") if value else "0"


def explain(
    event: Any, record: UpdateRecord, action_names: Sequence[str], describe: Callable[[Any], str],
    title: str = "", describe_row: Callable[[int], str] | None = None,
) -> list[tuple[str, str]]:
    """The panel's lines as (label, text) pairs for one step and its update record.
    `describe` puts an observation in words; `describe_row` a row of the table (the
    states Monte Carlo updates at an episode's end are rows)."""

    def name(action: int | None) -> str:
        if action is None:
            return "–"
        return action_names[action] if 0 <= action < len(action_names) else str(action)

    def state(observation: Any, row: int) -> str:
        try:
            return describe(observation)
        except Exception:  # wrappers may change what an observation looks like
            return row_words(row)

    def row_words(row: int) -> str:
        try:
            return describe_row(row) if describe_row is not None else f"state {row}"
        except Exception:  # a table whose rows are not states in words
            return f"state {row}"

    lines: list[tuple[str, str]] = []
    where = f"episode {event.episode:,} · step {event.step:,}" if event.step else ""
    lines.append(("", " · ".join(part for part in (title, where) if part)))
    lines.append(("s", state(event.observation, record.state)))
    lines.append(("a", f"{name(record.action)}    r = {_num(record.reward)}"))
    ending = " (terminal)" if record.terminated else " (time limit)" if record.truncated else ""
    lines.append(("s'", state(event.next_observation, record.next_state) + ending))
    if record.table:
        lines.append(("table", f"a coin picked Q_{record.table} to update"))
    if record.target_action is not None:
        what = "a' it will take" if record.next_action is not None and not record.table else (
            "a* = argmax of the updated table"
        )
        lines.append(("a'", f"{name(record.target_action)}  ({what})"))
    lines.extend(record.notes)
    terms = "   ".join(f"{symbol} = {_num(value)}" for symbol, value in record.terms)
    if len(record.terms) == 1 and record.formula.rpartition("=")[2].strip() == record.terms[0][0]:
        terms = ""  # the target is the one term ('r' at the end): said once, on its line

    if record.target is None:
        lines.append(("target", f"{record.formula}: nothing is updated before then"))
    else:
        lines.append(("target", f"{record.formula} = {_num(record.target)}"))
    if terms:
        lines.append(("", terms))
    count = len(record.episode_updates)
    if record.target is not None and record.episode_return is not None:
        lines.append(("return", f"G = {_num(record.episode_return)} from the episode's start; "
                                f"{count} update{'s' if count != 1 else ''} at its end"))
    for update in record.episode_updates[:EPISODE_UPDATES_SHOWN]:
        moved = (f"e = {_num(update.trace)}" if update.trace is not None
                 else f"G = {_num(update.target)}")
        lines.append(("", f"{row_words(update.state)}, {name(update.action)}: {moved}  "
                          f"Q {_num(update.before)} → {_num(update.after)}"))
    if count > EPISODE_UPDATES_SHOWN:
        lines.append(("", f"... {count - EPISODE_UPDATES_SHOWN} more"))
    if record.target is None:
        lines.append(("Q(s,a)", f"{_num(record.before)} (unchanged)"))
        return lines
    assert record.td_error is not None and record.step_size is not None
    lines.append(("TD error", f"target − Q(s,a) = {_num(record.target)} − {_num(record.before)}"
                              f" = {_num(record.td_error)}"))
    lines.append(("Q(s,a)", f"{_num(record.before)} → {_num(record.after)}   "
                            f"(step α = {record.step_size:.4g})"))
    if record.planning_updates:
        updates = plural(record.planning_updates, "simulated update")
        lines.append(("planning", f"then {updates} from the model"))
    return lines


class StepPanel(Static):
    """The explanation of the last step (see the module docstring)."""

    DEFAULT_CSS = panel_css("StepPanel", compact=False)

    def __init__(self, *, id: str | None = None, classes: str | None = None) -> None:
        super().__init__("", id=id, classes=classes)
        self.border_title = "The update, step by step"
        self.lines: list[tuple[str, str]] = []

    def show(self, lines: list[tuple[str, str]]) -> None:
        """Show lines from `explain` (none: a hint how to get some)."""
        self.lines = lines
        if not lines:
            self.update(Text("n: take one step and see how the learner uses it", style="dim"))
            return
        width = max(len(label) for label, _ in lines)
        text = Text()
        for i, (label, body) in enumerate(lines):
            if i:
                text.append("\n")
            if i == 0:
                text.append(body, style="bold")
                continue
            text.append(label.ljust(width) + "  ", style="bold" if label else "")
            text.append(body)
        self.update(text)
