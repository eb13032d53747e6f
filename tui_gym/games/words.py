"""Words and numbers for people, shared by every game's narrator."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from tui_gym.core.text import json_safe

if TYPE_CHECKING:
    from tui_gym.session.play import Scorecard, Tally

__all__ = [
    "MIN_CI_EPISODES", "ScoreRow", "agreement_summary", "format_reward", "interval_text",
    "join_parts", "plural", "return_summary", "signed", "to_jsonable", "unwrapped_note",
    "watched_row",
]

to_jsonable = json_safe  # numpy values, tuples and dicts as plain JSON data

MIN_CI_EPISODES = 30  # episodes before a mean's 95% interval is shown (normal approximation)


class ScoreRow(NamedTuple):
    """One line of a scoreboard: who ("You", "Agent", "Optimum", "Watched") and how,
    in full and in a few words (`short`, for narrow screens; the full text if empty)."""

    who: str
    text: str
    short: str = ""


def format_reward(value: float) -> str:
    """A reward for people: '+1', '−1' (a true minus sign), '0', '+1.5'."""
    if value == 0:
        return "0"
    text = f"{abs(value):.4g}"
    return ("+" if value > 0 else "\u2212") + text


def signed(value: float, places: int) -> str:
    """A number with its sign for people: '+0.125', '−0.290' (a true minus), '0.000'."""
    text = f"{abs(value):.{places}f}"
    if float(text) == 0:
        return text
    return ("+" if value > 0 else "\u2212") + text


def plural(count: int, noun: str) -> str:
    """'1 hand', '3 hands', '1,200 hands'."""
    return f"{count:,} {noun}{'' if count == 1 else 's'}"


def return_summary(tally: Tally, noun: str, short: bool = False) -> str:
    """'mean return −0.125 ± 0.412 (95% CI) over 38 hands' or 'no hands played yet';
    `short`: '−0.125 ± 0.412 over 38 hands'. Below `MIN_CI_EPISODES` the
    interval shows as '–' (a handful of hands says little about its width)."""
    if not tally.episodes:
        return f"no {noun}s yet" if short else f"no {noun}s played yet"
    text = signed(tally.mean, 3) if short else f"mean return {signed(tally.mean, 3)}"
    text += " ± " + interval_text(tally) + ("" if short else " (95% CI)")
    return f"{text} over {plural(tally.episodes, noun)}"


def interval_text(tally: Tally) -> str:
    """The half-width of the 95% interval of the mean return ('0.412'), or '–' while
    fewer than `MIN_CI_EPISODES` episodes make it."""
    low, high = tally.confidence_interval(min_episodes=MIN_CI_EPISODES)
    return "–" if low != low else f"{(high - low) / 2:.3f}"  # NaN: too few episodes


def agreement_summary(
    card: Scorecard, words: str = "moves as the optimum", short: bool = False
) -> str:
    """'9/11 moves as the optimum (82%)', `short` '82% optimal' ('' before a decision)."""
    if card.agreement is None:
        return ""
    if short:
        return f"{card.agreement:.0%} optimal"
    return f"{card.agreed}/{card.decisions} {words} ({card.agreement:.0%})"


def watched_row(
    card: Scorecard, noun: str, words: str = "moves as the optimum", extra: str = ""
) -> ScoreRow:
    """What the agent did while a person watched: episodes, mean return, agreement."""
    tally = card.tally
    text = f"the agent played {plural(tally.episodes, noun)}, mean return {signed(tally.mean, 3)}"
    short = f"agent: {plural(tally.episodes, noun)}, {signed(tally.mean, 3)}"
    return ScoreRow(
        "Watched", join_parts(text, agreement_summary(card, words), extra),
        join_parts(short, extra),
    )


def join_parts(*parts: str) -> str:
    """Non-empty parts joined with " · "."""
    return " · ".join(part for part in parts if part)


def unwrapped_note(names: tuple[str, ...] | list[str]) -> str:
    """'figures of the unwrapped game: StickyAction changes it'."""
    verb = "changes" if len(names) == 1 else "change"
    return f"figures of the unwrapped game: {', '.join(names)} {verb} it"
