"""The recording format: JSON lines, one object a line, versioned by its header."""

from __future__ import annotations

import json
from typing import Any

from tui_gym.core.text import json_safe

FORMAT_NAME = "tui-gym-recording"
FORMAT_VERSION = 1
SUFFIX = ".jsonl"

HEADER, START, STEP, END = "header", "start", "step", "end"

OPTIMAL, NOT_OPTIMAL = VERDICTS = ("optimal", "not optimal")


def encode_line(record: dict[str, Any]) -> bytes:
    """One record as a line of ASCII JSON ending in a newline."""
    return (json.dumps(json_safe(record), allow_nan=False, default=str) + "\n").encode("ascii")
