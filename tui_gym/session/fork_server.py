"""Loaded by the training processes' fork server before it forks any: the engine and Numba's
CPU target set up there once, so each child loads its learner's compiled code at once."""

import contextlib

from tui_gym.core.engine import jit

with contextlib.suppress(Exception):  # a child then sets it up itself, as without the server
    jit.prepare()
