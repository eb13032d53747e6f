"""The recording format: JSON lines, one object a line, versioned by its header."""

from __future__ import annotations

import json
import math
import re
from typing import Any

FORMAT_NAME = "tui-gym-recording"
FORMAT_VERSION = 1
SUFFIX = ".jsonl"

HEADER, START, STEP, END = "header", "start", "step", "end"

VERDICTS = ("optimal", "not optimal")

_SURROGATE = re.compile("[\ud800-\udfff]")


def clean(value: Any) -> Any:
    """JSON-safe data: numpy values as plain ones, NaN and infinities as null, lone
    surrogates as U+FFFD, tuples as lists."""
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):  # numpy arrays, scalars
        value = value.tolist()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, str):
        return _SURROGATE.sub("\ufffd", value)
    if isinstance(value, dict):
        return {clean(str(k)): clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [clean(v) for v in value]
    return value


def encode_line(record: dict[str, Any]) -> bytes:
    """One record as a line of ASCII JSON ending in a newline."""
    return (json.dumps(clean(record), allow_nan=False, default=str) + "\n").encode("ascii")
