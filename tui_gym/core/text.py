"""Text that came from a file or another program, made safe to show (`visible`); JSON data
checked for nesting (`nested_deeper`) and made safe to write (`json_safe`)."""

from __future__ import annotations

import math
import re
import unicodedata
from typing import Any

__all__ = ["json_safe", "nested_deeper", "visible"]

# Control (Cc), format (Cf: bidirectional overrides, zero-width marks), line and paragraph
# separators, surrogates and unassigned code points.
_HIDDEN = frozenset({"Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn"})


def _escaped(char: str) -> str:
    code = ord(char)
    if code < 0x100:
        return f"\\x{code:02x}"
    if code < 0x10000:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def visible(text: object, limit: int | None = 80) -> str:
    """`text` with every control or invisible character written as an escape, cut to
    `limit` characters (None: never cut); a cut string says how long it was."""
    raw = text if isinstance(text, str) else str(text)
    if (limit is None or len(raw) <= limit) and raw.isprintable():
        return raw  # the common case, checked at C speed: nothing to escape or cut
    most = len(raw) if limit is None else 4 * limit  # enough to fill `limit` after escaping
    cut = len(raw) > most
    shown = "".join(_escaped(c) if unicodedata.category(c) in _HIDDEN else c for c in raw[:most])
    if limit is None or (not cut and len(shown) <= limit):
        return shown
    keep = max(1, limit - 1)
    return f"{shown[:keep]}… ({len(raw):,} characters)"


def nested_deeper(value: Any, limit: int) -> bool:
    """Whether lists and objects in `value` nest deeper than `limit` (without recursion)."""
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            if depth > limit:
                return True
            stack.extend((child, depth + 1) for child in (
                item.values() if isinstance(item, dict) else item
            ))
    return False


_SURROGATE = re.compile("[\ud800-\udfff]")


def json_safe(value: Any) -> Any:
    """JSON-safe data: numpy values as plain ones, NaN and infinities as null, lone
    surrogates as U+FFFD, keys as text, tuples as lists."""
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):  # numpy arrays, scalars
        value = value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, str):
        return _SURROGATE.sub("\ufffd", value)
    if isinstance(value, dict):
        return {json_safe(str(k)): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value
