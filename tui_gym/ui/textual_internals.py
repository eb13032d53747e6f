"""Every private name of Textual the app uses, each with a fallback to Textual's own behaviour.

Each part checks that the names it needs are there with the shape it expects, else (or
when `TUI_GYM_STOCK_TEXTUAL` names it; `all` names every one) leaves Textual to itself:

- `compositor`: the main screen's compositor keeps the layout a pass made and draws only
  the lines an update shows (`main_screen`, `in_sight`);
- `resume`: the main screen's widgets keep their styles when it first shows;
- `focus`: a focus change restyles and repaints only what it changes;
- `crash`: an app that owns its terminal keeps a traceback off the screen (`CrashHook`);
- `ticks`: the run list's tick boxes read ✓ when ticked (`ticked_line`);
- `terminal`: a closed terminal or pipe ends the app, and writes to it never block
  (`guarded_driver`, `terminal_write_failed`);
- `frames`: `tui-gym bench` times the frames and delivers keys as the terminal driver
  does (`watch_frames`, `deliver_key`).
"""

from __future__ import annotations

import functools
import inspect
import os
import select
import threading
from collections.abc import Callable, Iterable
from typing import Any

from rich.segment import Segment
from textual.app import App
from textual.dom import DOMNode
from textual.driver import Driver
from textual.events import ScreenResume
from textual.geometry import Region, Size
from textual.message import Message
from textual.reactive import Reactive
from textual.screen import Screen
from textual.strip import Strip
from textual.widget import Widget

STOCK_ENV = "TUI_GYM_STOCK_TEXTUAL"
PARTS = ("compositor", "resume", "focus", "crash", "ticks", "terminal", "frames")

def enabled(part: str) -> bool:
    """Whether `part` uses Textual's private names (`TUI_GYM_STOCK_TEXTUAL` may turn it off)."""
    stock = {word.strip() for word in os.environ.get(STOCK_ENV, "").lower().split(",")}
    return not ({"all", "1", part} & stock)


def _parameters(function: Any) -> list[str]:
    try:
        return list(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return []


# --- the main screen: compositor and first show -----------------------------------------
@functools.cache
def _compositor_class() -> type | None:
    """`Compositor` subclassed to keep its layout (None when its shape is not the one known)."""
    try:
        from textual._compositor import Compositor
    except ImportError:
        return None
    needed = ("reflow", "render_partial_update", "_render_chops", "_regions_to_spans",
              "visible_widgets", "cuts")
    if not all(hasattr(Compositor, name) for name in needed):
        return None
    if _parameters(Compositor._render_chops) != ["self", "crop", "is_rendered_line"]:
        return None

    class KeptLayoutCompositor(Compositor):  # type: ignore[misc, valid-type]
        """Textual's compositor, keeping the full map a layout pass has just made (Textual
        leaves it stale, so the next region asked for lays the screen out again), and
        drawing of each widget only the lines where a stretch to repaint is still open
        in front of it (Textual draws every widget meeting the update's box in full)."""

        _spans: list[tuple[int, int, int]] | None = None  # (y, x1, x2) a partial update repaints

        def reflow(self, parent: Widget, size: Size) -> Any:
            result = super().reflow(parent, size)
            self._full_map_invalidated = False  # the map just made is the full one
            return result

        def render_partial_update(self) -> Any:
            self._spans = list(self._regions_to_spans(getattr(self, "_dirty_regions", ())))
            try:
                return super().render_partial_update()
            finally:
                self._spans = None

        def _render_chops(
            self, crop: Region, is_rendered_line: Callable[[int], bool]
        ) -> Any:
            cuts = self.cuts
            chops: list[dict[int, Strip | None]] = [dict.fromkeys(line[:-1]) for line in cuts]
            wanted = self._wanted(cuts, is_rendered_line)  # per line, the stretches still open
            for widget, (region, clip) in self.visible_widgets.items():  # front to back
                visible = region.intersection(clip)
                if not (visible.width and visible.height and crop.overlaps(visible)):
                    continue
                left, right = visible.column_span
                open_lines = [
                    y for y in visible.line_range
                    if any(left <= cut < right for cut in wanted[y])
                ]
                if not open_lines:
                    continue  # nothing to repaint, or covered by the widgets in front
                top, bottom = open_lines[0], open_lines[-1] + 1
                drawn = Region(left, top, right - left, bottom - top)
                strips = widget.render_lines(drawn.translate(-region.offset))
                for y, strip in zip(range(top, bottom), strips, strict=False):
                    if not is_rendered_line(y):
                        continue
                    line, want = chops[y], wanted[y]
                    line_cuts = [cut for cut in cuts[y] if left <= cut <= right]
                    pieces = strip.divide([cut - left for cut in line_cuts[1:]])
                    for cut, piece in zip(line_cuts, pieces, strict=False):  # the last cut ends it
                        if line.get(cut) is None:
                            line[cut] = piece
                            want.discard(cut)
            return chops

        def _wanted(
            self, cuts: list[list[int]], is_rendered_line: Callable[[int], bool]
        ) -> list[set[int]]:
            """For each line, the cuts starting a stretch the update shows."""
            spans = self._spans
            if spans is None:  # the whole screen
                return [set(line[:-1]) if is_rendered_line(y) else set()
                        for y, line in enumerate(cuts)]
            wanted: list[set[int]] = [set() for _ in cuts]
            for y, x1, x2 in spans:
                if 0 <= y < len(cuts):
                    line = cuts[y]
                    wanted[y].update(cut for cut, end in zip(line, line[1:], strict=False)
                                     if cut < x2 and end > x1)
            return wanted

    probe = KeptLayoutCompositor()
    if not hasattr(probe, "_full_map_invalidated") or not hasattr(probe, "_dirty_regions"):
        return None
    return KeptLayoutCompositor


class _ResumingScreen(Screen):
    """A screen that, the first time it shows, keeps the styles its widgets were
    mounted with instead of styling them all over again."""

    _shown = False

    def _on_screen_resume(self, event: ScreenResume) -> None:
        # Runs before `Screen`'s own handler, which restyles every node when asked to.
        if not self._shown:
            self._shown = True
            if enabled("resume") and hasattr(event, "refresh_styles"):
                event.refresh_styles = False


_FOCUS_STATES = frozenset({"focus", "blur", "focus-within"})
_FRAME_STYLES = ("border", "auto_border", "outline")  # a widget's frame: not drawn inside


def _focus_styles_its_own(widget: Widget) -> bool:
    """Whether a focus change of `widget` restyles no widget inside it: no rule reads the
    focus of a widget around the one it styles, and the rules that read `widget`'s own
    focus set only its border and outline (the widgets inside draw with neither)."""
    try:
        stylesheet = widget.app.stylesheet
        names = widget._selector_names
        for rule in stylesheet.rules:
            for selectors in rule.selector_set:
                *around, last = selectors.selectors
                if any(_FOCUS_STATES & selector.pseudo_classes and selector._check(widget)
                       for selector in around):
                    return False
                if (_FOCUS_STATES & last.pseudo_classes and names & rule.selector_names
                        and not all(key.startswith(_FRAME_STYLES)
                                    for key in rule.styles.get_rules())):
                    return False
    except Exception:  # a stylesheet of another shape: restyle as Textual does
        return False
    return True


def _hidden(widget: DOMNode) -> bool:
    """Whether `widget` is out of the layout (it, or a widget around it, has no display)."""
    return not all(node.display for node in widget.ancestors_with_self)


def _own_focus_styler(widget: Widget) -> Callable[[], None]:
    """`widget`'s watcher of its focus: it restyles the widget alone where it can, and
    after the next frame when the widget is hidden (the view it sits in was switched away)."""

    def restyle() -> None:
        if not widget.is_attached:
            return
        if widget.children and not _focus_styles_its_own(widget):
            widget.update_node_styles()  # Textual's own: the widget and all inside it
        else:
            widget.app.stylesheet.update_nodes([widget], animate=True)

    def watch_has_focus() -> None:
        if _hidden(widget):
            widget.call_after_refresh(restyle)
        else:
            restyle()

    return watch_has_focus


class _QuietFocusScreen(_ResumingScreen):
    """A screen whose focus change repaints only what it restyles, restyling the widget
    alone where nothing inside it can change (a hidden one after the next frame)."""

    focused: Reactive[Widget | None] = Reactive(None, repaint=False)

    def set_focus(self, widget: Widget | None, *args: Any, **kwargs: Any) -> None:
        if (widget is not None and "watch_has_focus" not in vars(widget)
                and type(widget).watch_has_focus is Widget.watch_has_focus):
            widget.watch_has_focus = _own_focus_styler(widget)  # type: ignore[method-assign, assignment]
        super().set_focus(widget, *args, **kwargs)

    def _update_focus_styles(
        self, focused: Widget | None = None, blurred: Widget | None = None
    ) -> None:
        if blurred is not None and _hidden(blurred) and not any(
                node._has_focus_within and not _hidden(node) for node in blurred.ancestors):
            # Nothing it restyles is on the screen: after the frame that hid it.
            self.call_after_refresh(super()._update_focus_styles, None, blurred)
            blurred = None
        super()._update_focus_styles(focused, blurred)


def main_screen(**kwargs: Any) -> Screen:
    """The app's main screen, with the parts that are enabled and fit this Textual."""
    quiet = (enabled("focus") and isinstance(vars(Screen).get("focused"), Reactive)
             and _parameters(Screen._update_focus_styles) == ["self", "focused", "blurred"])
    screen = (_QuietFocusScreen if quiet else _ResumingScreen)(**kwargs)
    if enabled("compositor") and hasattr(screen, "_compositor"):
        compositor = _compositor_class()
        if compositor is not None:
            screen._compositor = compositor()
    return screen


def in_sight(widget: Widget) -> bool:
    """Whether `widget` was in sight in its screen's last frame: on the screen's map, not
    hidden, scrolled or clipped away (False when this Textual does not tell cheaply)."""
    if not enabled("compositor"):
        return False
    try:
        return widget in widget.screen._compositor.visible_widgets
    except Exception:  # no screen, or a compositor of another shape
        return False


# --- an unexpected error --------------------------------------------------------------------
class CrashHook:
    """An `App` mixin: `crash` holds the first unexpected error; with `quiet_crash` set,
    its traceback is not printed on the terminal when the app ends (the app logs it)."""

    crash: BaseException | None = None
    quiet_crash = False

    def _handle_exception(self, error: Exception) -> None:
        # Textual's one path for an unhandled error: it ends the app with code 1 and
        # keeps a traceback to print on the terminal.
        if self.crash is None:
            self.crash = error
        super()._handle_exception(error)  # type: ignore[misc]
        kept = getattr(self, "_exit_renderables", None)
        if self.quiet_crash and enabled("crash") and isinstance(kept, list):
            kept.clear()


# --- the run list's tick marks -----------------------------------------------------------
def _button_inner() -> str | None:
    try:
        from textual.widgets._toggle_button import ToggleButton
    except ImportError:
        return None
    inner = getattr(ToggleButton, "BUTTON_INNER", None)
    return inner if isinstance(inner, str) and len(inner) == 1 else None


def ticked_line(strip: Strip, ticked: Callable[[], bool]) -> Strip:
    """A `SelectionList` line with its tick box reading ✓ when `ticked()` (Textual's box
    draws the same mark on and off); the line as Textual drew it otherwise."""
    inner = _button_inner() if enabled("ticks") else None
    segments = list(strip)
    if inner is None or len(segments) < 3 or segments[1].text != inner:
        return strip
    try:
        mark = "✓" if ticked() else " "
    except Exception:  # the option asked about is gone: leave the line as drawn
        return strip
    segments[1] = Segment(mark, segments[1].style)
    return Strip(segments, strip.cell_length)


# --- the terminal going away ----------------------------------------------------------------
class TerminalGone(Message):
    """The terminal, or the pipes a served app talks through, closed: nobody is left to
    see the app or type to it."""


_HANGUP = select.POLLHUP | select.POLLERR | select.POLLNVAL
WATCH_SECONDS = 0.25  # how often the watcher looks at the terminal


class _Guard:
    """The file descriptors a driver reads and writes, watched for a hang-up (a poll
    object for each look: they may come from several threads at once)."""

    def __init__(self, fds: Iterable[int]) -> None:
        self.fds = tuple(fds)
        self.gone = False
        self.stopped = threading.Event()

    def hung_up(self, timeout_ms: int = 0) -> bool:
        """Whether the terminal or a pipe closed, waiting up to `timeout_ms` for it."""
        if not self.gone:
            poll = select.poll()
            for fd in self.fds:
                poll.register(fd, _HANGUP)
            self.gone = bool(poll.poll(timeout_ms))
        return self.gone


def _driver_fds(driver: Driver) -> list[int]:
    """The input and the output a driver uses (stdin, and stdout or stderr)."""
    import sys

    streams = (sys.__stdin__, sys.__stdout__ if driver.is_web else sys.__stderr__)
    fds = []
    for stream in streams:
        try:
            fds.append(stream.fileno())  # type: ignore[union-attr]
        except (AttributeError, OSError, ValueError):
            continue
    return fds


def guarded_driver(base: type[Driver]) -> type[Driver]:
    """`base` made to notice a closed terminal or pipes: it posts `TerminalGone`, drops
    what it would write from then on (a write queued behind a dead writer thread would
    wait for good), and stops without waiting on that writer."""
    if not enabled("terminal") or not hasattr(select, "poll"):
        return base
    needed = ("write", "flush", "close", "start_application_mode", "stop_application_mode")
    if not all(callable(getattr(base, name, None)) for name in needed):
        return base
    if _parameters(base.__init__)[:2] != ["self", "app"]:
        return base

    class Guarded(base):  # type: ignore[misc, valid-type]
        def __init__(self, app: App[Any], **kwargs: Any) -> None:
            super().__init__(app, **kwargs)
            self.owner = app
            self.guard = _Guard(_driver_fds(self))
            self.watcher: threading.Thread | None = None

        def start_application_mode(self) -> None:
            # Again on a resume (after ctrl+z, or the SIGCONT a hang-up may send): one
            # watcher at a time.
            self.guard.stopped.clear()
            if self.watcher is None or not self.watcher.is_alive():
                self.watcher = threading.Thread(target=self._watch, name="tui-gym-terminal",
                                                daemon=True)
                self.watcher.start()
            super().start_application_mode()

        def _watch(self) -> None:
            guard = self.guard
            while not guard.stopped.is_set():
                if guard.hung_up(int(WATCH_SECONDS * 1000)):
                    self.owner.post_message(TerminalGone())
                    return

        def _unless_gone(self, call: Callable[..., None], *args: Any) -> None:
            """`call(*args)` while the terminal is there; an OSError says it has gone."""
            if not self.guard.hung_up():
                try:
                    call(*args)
                except OSError:
                    self.guard.gone = True

        def write(self, data: str) -> None:
            self._unless_gone(super().write, data)

        def flush(self) -> None:
            self._unless_gone(super().flush)

        def run_input_thread(self) -> None:
            try:
                super().run_input_thread()
            except OSError:  # reading a closed terminal: the watcher says so
                self.guard.gone = True

        def stop_application_mode(self) -> None:
            self.guard.stopped.set()
            try:
                super().stop_application_mode()  # a web driver writes its goodbye itself
            except OSError:
                if not self.guard.hung_up():
                    raise

        def close(self) -> None:
            if not self.guard.hung_up():
                super().close()  # else its writer may never take another line

    Guarded.__name__ = Guarded.__qualname__ = f"Guarded{base.__name__}"
    return Guarded


WRITER_THREAD = "textual-output"  # the name of the thread a terminal driver writes from


def terminal_write_failed(args: threading.ExceptHookArgs) -> bool:
    """Whether a thread's failure is the terminal driver's writer finding the terminal
    gone (a write it had queued before the app knew); False when not known."""
    thread = args.thread
    return (enabled("terminal") and thread is not None and thread.name == WRITER_THREAD
            and isinstance(args.exc_value, OSError))


# --- the bench's hooks -----------------------------------------------------------------------
def watch_frames(app: App[Any], on_frame: Callable[[Any], None]) -> bool:
    """Call `on_frame(renderable)` each time `app` hands a screen update to its driver;
    False (and nothing hooked) when this Textual has no such step to hook."""
    display = getattr(app, "_display", None)
    if not enabled("frames") or not callable(display) or _parameters(display) != [
        "screen", "renderable"
    ]:
        return False

    def timed_display(screen: Any, renderable: Any) -> None:
        display(screen, renderable)
        if renderable is not None:
            on_frame(renderable)

    app._display = timed_display  # type: ignore[method-assign]
    return True


def deliver_key(app: App[Any], event: Message) -> None:
    """Hand `app` a key event as the terminal driver does (from outside its queue)."""
    driver = getattr(app, "_driver", None)
    send = getattr(driver, "send_message", None)
    if enabled("frames") and callable(send):
        send(event)
    else:
        app.post_message(event)
