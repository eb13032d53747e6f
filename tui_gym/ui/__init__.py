"""Textual front end: the app, its screens and widgets. Never imports gymnasium.

Importing this package sets Textual's frame-rate cap (`TEXTUAL_FPS`, read
once when Textual is first imported) to `MAX_FPS` unless it is set already.
Textual draws a changed screen on the next tick of a timer at that rate, and
after a frame that took longer than a tick it skips a tick. While training,
a frame is drawn 15 times a second and takes about 11 ms, so at Textual's
default of 60 a key press could wait 33 ms for its frame to start; at 240 it
waits at most 8. The cap only sets how soon a change is drawn: an unchanged
screen is never drawn again.
"""

import os

MAX_FPS = 240
os.environ.setdefault("TEXTUAL_FPS", str(MAX_FPS))
