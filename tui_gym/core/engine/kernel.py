"""`@kernel`: marks a plain Python function as compiled code, plain Python until `jit.start()`
(`inline=True`: compiled into each caller, for a small one)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["KERNELS", "LOCK", "kernel"]

F = TypeVar("F", bound=Callable[..., Any])

KERNELS: list[Callable[..., Any]] = []
INLINE: set[Callable[..., Any]] = set()
LOCK = threading.RLock()
# Set by `jit.start`: compiles a kernel marked later, at once.
compile_now: Callable[[Callable[..., Any]], Any] | None = None


def kernel(fn: F | None = None, *, inline: bool = False) -> Any:
    """Mark `fn` as compiled code (see the module docstring)."""

    def mark(fn: F) -> F:
        with LOCK:
            KERNELS.append(fn)
            if inline:
                INLINE.add(fn)
            if compile_now is not None:
                return compile_now(fn)  # type: ignore[no-any-return]
        return fn

    return mark if fn is None else mark(fn)
