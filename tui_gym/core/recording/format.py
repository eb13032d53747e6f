"""The recording format: JSON lines, one object a line, versioned by its header.

A recording is a text file of JSON objects, one a line, each with a `type`:

- `header`: `format` ("tui-gym-recording"), `version` (`FORMAT_VERSION`),
  `tui_gym` (the version that wrote it), `source` (who played: "play",
  "benchmark", "app"), `game`, `title`, `env_id`, `env_kwargs`, `wrappers`
  (as `--wrapper` takes them, innermost first), `seed`, `board` (the kind of
  board that draws the game's scenes), `actions` (names by number),
  `episode_noun` and `created` (UTC, ISO 8601). A file starts with one; another
  comes wherever the game, its parameters or its wrappers change, and applies
  to the episodes after it.
- `start`: an episode begins: `episode` (counted from 1 in the file), `seed`
  (when the reset was seeded), `observation` (JSON data), `scene` (what the
  board draws), `text` (the state in words), `info`.
- `step`: one move: `episode`, `step` (from 1), `action` and `action_name`,
  `reward`, `terminated`, `truncated`, the resulting `observation`, `scene`,
  `text` and `info`, and the coach's judgement of the move: `verdict`
  ("optimal", "not optimal", or null where there was no optimum to judge by),
  `regret` (`max_a Q*(s,·) − Q*(s,a)` in exact expected return, or null where
  exact action values are unknown) and `optimal` (the optimal actions' names).
  An optional `note` says something about the move (e.g. a default action).
- `end`: the episode is over: `episode`, `steps`, `return`, `terminated`,
  `truncated` (both false: abandoned before its end) and `regret` (the sum of
  the moves' regrets, null when one was unknown).

Numbers that JSON cannot hold (NaN, infinities) are written as null.
"""

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
    return (json.dumps(clean(record), allow_nan=False, default=str) + "\n").encode(
        "ascii"
    )
