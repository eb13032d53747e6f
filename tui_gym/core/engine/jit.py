"""The one module that imports Numba: kernels compiled on first use, cached on disk.

The cache folder is keyed by a hash of the engine's and the algorithms' sources (Numba does
not see a change in a callee's file). Kernels allocate nothing: no reference counting, no C
wrapper, `NUMBA_OPT` 1 unless set. Processes take turns to file what they compiled
(`saving`): Numba numbers cache entries by counting its index.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import sys
from collections.abc import Callable, Iterator
from functools import cache
from pathlib import Path
from typing import Any

from tui_gym.core.engine import kernel

__all__ = [
    "COMPILING",
    "cache_folder",
    "compiled",
    "compiles",
    "direct",
    "entry",
    "folder",
    "prepare",
    "saving",
    "start",
]

COMPILING = "compiling the learners, once"

_PACKAGE = Path(__file__).resolve().parents[2]  # tui_gym/
_SOURCES = ("core/engine", "algorithms")  # what compiled code is made of
_OPTIONS: Any = {"cache": True, "_nrt": False, "no_cfunc_wrapper": True}  # see the docstring
_COMPILED: dict[Callable[..., Any], Any] = {}
_ENTRIES: dict[tuple[Callable[..., Any], object], Any] = {}
_started = False
_folder: Path | None = None
_saves_in_turn = False  # set by `start` (see the module docstring)


def compiles() -> bool:
    """Whether kernels compile (not with `NUMBA_DISABLE_JIT`)."""
    return os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0")


def folder() -> Path:
    """The cache folder in use (the engine is started first)."""
    start()
    assert _folder is not None
    return _folder


def sources_hash() -> str:
    """A short hash of every source file compiled code is made from."""
    digest = hashlib.sha256()
    for part in _SOURCES:
        for path in sorted((_PACKAGE / part).glob("*.py")):
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _writable(place: Path) -> bool:
    try:
        place.mkdir(parents=True, exist_ok=True)
        probe = place / f".probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError:
        return False
    return True


def cache_folder(environ: dict[str, str] | None = None) -> Path:
    """Where compiled code is kept: under `NUMBA_CACHE_DIR` when set, else the package's
    `__pycache__`, else (a read-only package) the user's cache folder."""
    env = os.environ if environ is None else environ
    name = f"numba-{sources_hash()}"
    given = env.get("NUMBA_CACHE_DIR", "")
    if given:  # a child process inherits the folder its parent chose: the same one
        return Path(given) if Path(given).name == name else Path(given) / name
    beside = _PACKAGE / "__pycache__" / name
    if _writable(beside):
        return beside
    xdg = env.get("XDG_CACHE_HOME", "")
    root = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return root / "tui-gym" / name


def start() -> None:
    """Import Numba and compile every kernel on first use (idempotent, thread-safe)."""
    global _started, _folder, _saves_in_turn
    if _started:
        return
    with kernel.LOCK:
        if _started:
            return
        chosen = cache_folder()
        chosen.mkdir(parents=True, exist_ok=True)
        os.environ["NUMBA_CACHE_DIR"] = str(chosen)
        os.environ.setdefault("NUMBA_OPT", "1")
        _folder = chosen
        import numba  # after the cache folder is set

        numba.config.CACHE_DIR = str(chosen)  # type: ignore[attr-defined]  # imported before

        from tui_gym.core.engine import rules

        _saves_in_turn = _save_in_turn()
        _register_overloads(rules)
        for fn in list(kernel.KERNELS):
            _compile(fn)
        kernel.compile_now = _compile
        _started = True


def prepare() -> None:
    """Start the engine and set up Numba's CPU target now, as the first load of compiled code
    would: a process forked after this (a fork server's child) loads its learner at once."""
    start()
    if not compiles():
        return
    with contextlib.suppress(ImportError, AttributeError):  # else the first load sets it up
        from numba.core.registry import cpu_target

        cpu_target.target_context.refresh()
        cpu_target.typing_context.refresh()


def _compile(fn: Callable[..., Any]) -> Any:
    """`fn` compiled, and put in its place in every `tui_gym` module that holds it."""
    from numba import njit

    compiled = _COMPILED.get(fn)
    if compiled is None:
        inline: Any = "always" if fn in kernel.INLINE else "never"
        compiled = _COMPILED[fn] = njit(**_OPTIONS, inline=inline)(fn)
        for name, module in list(sys.modules.items()):
            if module is None or not (name == "tui_gym" or name.startswith("tui_gym.")):
                continue
            for attr, value in list(vars(module).items()):
                if value is fn:
                    setattr(module, attr, compiled)
    return compiled


class _Entry:
    """A kernel's compiled form, called directly for the argument types of its last call."""

    def __init__(self, dispatcher: Any) -> None:
        self.dispatcher = dispatcher
        self._direct: Any = None

    def __call__(self, *args: Any) -> Any:
        direct = self._direct
        if direct is not None:
            try:
                return direct(*args)
            except (TypeError, ValueError):  # other argument types: look them up
                pass
        dispatcher = self.dispatcher
        if not hasattr(dispatcher, "compile"):  # NUMBA_DISABLE_JIT
            return dispatcher(*args)
        types = tuple(dispatcher.typeof_pyval(arg) for arg in args)
        if types not in dispatcher.overloads:
            with contextlib.nullcontext() if _saves_in_turn else saving():
                dispatcher.compile(types)
        self._direct = dispatcher.overloads[types].entry_point
        return self._direct(*args)


@contextlib.contextmanager
def saving() -> Iterator[None]:
    """Hold the cache folder's lock (a POSIX lock; none where the folder takes no file)."""
    try:
        handle = open(folder() / ".compile.lock", "a")  # noqa: SIM115 (held while saving)
    except OSError:
        yield
        return
    with handle:
        fcntl.lockf(handle, fcntl.LOCK_EX)
        yield  # closing the file lets the lock go


def _save_in_turn() -> bool:
    """Make Numba file each new cache entry under `saving`; False where its private
    `IndexDataCacheFile.save` is missing."""
    from numba.core import caching

    index = getattr(caching, "IndexDataCacheFile", None)
    save = getattr(index, "save", None)
    if index is None or save is None:
        return False
    if getattr(save, "in_turn", False):
        return True

    def save_in_turn(self: Any, key: Any, data: Any) -> None:
        with saving():
            save(self, key, data)

    save_in_turn.in_turn = True  # type: ignore[attr-defined]
    index.save = save_in_turn
    return True


def entry(fn: Callable[..., Any], kind: object) -> Any:
    """Kernel `fn` as called from Python with one algorithm's `Params` (`kind`), compiled
    apart (Numba types a NamedTuple from Python by its fields alone), without the GIL."""
    start()
    key = (fn, kind)
    if key not in _ENTRIES:
        from numba import njit

        _ENTRIES[key] = _Entry(njit(**_OPTIONS, nogil=True)(getattr(fn, "py_func", fn)))
    return _ENTRIES[key]


@cache
def direct(fn: Callable[..., Any], kind: object = None) -> Any:
    """Kernel `fn` as called from Python through the compiled form its compiled callers
    call, per `kind` (see `entry`)."""
    start()
    return _Entry(compiled(fn))


def compiled(fn: Callable[..., Any] | None) -> Any:
    """The compiled form of a kernel (itself when the engine runs plain Python)."""
    if fn is None:
        return None
    return _COMPILED.get(fn, fn)


def _register_overloads(rules: Any) -> None:
    """Each rule stub, compiled, dispatches on the type of its `hp` at compile time."""
    from numba.extending import overload

    _CACHED: Any = {"cache": True, "no_cfunc_wrapper": True}

    def rule_of(hp: Any) -> Any:
        return rules.RULES[hp.instance_class]

    @overload(rules.update, jit_options=_CACHED, inline="always")
    def _update(tables, hp, rng, offered, s, a, r, s2, terminated, truncated, a2, epsilon, log):
        rule = compiled(rule_of(hp).update)

        def impl(tables, hp, rng, offered, s, a, r, s2, terminated, truncated, a2, epsilon, log):
            return rule(
                tables, hp, rng, offered, s, a, r, s2, terminated, truncated, a2, epsilon, log
            )

        return impl

    def own_or(name: str, default: Callable[..., Any]) -> Callable[..., Any]:
        """The typing of stub `name`: the rule's own part, else `default`."""

        def typing(tables, hp):
            own = compiled(getattr(rule_of(hp), name))
            if own is None:
                return default

            def impl(tables, hp):
                return own(tables, hp)

            return impl

        return typing

    for name, default in (("acting", _first_table), ("begin", _nothing), ("full", _never)):
        overload(getattr(rules, name), jit_options=_CACHED, inline="always")(own_or(name, default))

    overload(rules.next_first, jit_options=_CACHED, inline="always")(
        lambda hp: _yes if rule_of(hp).next_first else _no
    )


# The rules' defaults: Numba wants an implementation's signature to be its typing's own.
def _first_table(tables, hp):
    return (tables[0],)


def _nothing(tables, hp):
    return None


def _never(tables, hp):
    return False


def _yes(hp):
    return True


def _no(hp):
    return False
