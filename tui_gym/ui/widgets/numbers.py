"""Numbers that fit: each figure in its full form and shorter ones, never cut (`fit`);
text cut to fit (`cut`)."""

from __future__ import annotations

from collections.abc import Sequence

Forms = tuple[str, ...]  # one figure's texts, fullest first


def compact_count(n: float) -> str:
    """A count in at most five characters: '9,999', '12.3k', '5.50M', '1.23B'."""
    n = float(n)
    if abs(n) < 10_000:
        return f"{n:,.0f}"
    units = (("k", 1e3), ("M", 1e6), ("B", 1e9))
    for i, (unit, size) in enumerate(units):
        scaled = n / size
        if abs(scaled) < 999.5 or i == len(units) - 1:  # 999.7k would round to 1000k
            digits = 2 if abs(scaled) < 9.995 else 1 if abs(scaled) < 99.95 else 0
            return f"{scaled:.{digits}f}{unit}"
    return f"{n:,.0f}"


def count_forms(n: float) -> Forms:
    """'5,496,812', then '5.50M'."""
    full = f"{n:,.0f}"
    short = compact_count(n)
    return (full, short) if short != full else (full,)


def number_forms(value: float, spec: str) -> Forms:
    """`value` as the format `spec` writes it ('+.4f'), then with fewer significant digits
    (4, 3, 2), signed alike: only the forms that are shorter."""
    forms = [format(value, spec)]
    sign = "+" if spec.startswith("+") else ""
    for digits in (4, 3, 2):
        text = f"{value:{sign}.{digits}g}"
        if len(text) < len(forms[-1]):
            forms.append(text)
    return tuple(forms)


def fit(forms: Sequence[str], width: int) -> str:
    """The fullest form at most `width` characters long (the shortest when none is)."""
    for text in forms:
        if len(text) <= width:
            return text
    return forms[-1]


def cut(text: str, width: int) -> str:
    """`text` in at most `width` characters, ending in '…' where it is cut."""
    return text if len(text) <= width else text[: max(0, width - 1)] + "…"
