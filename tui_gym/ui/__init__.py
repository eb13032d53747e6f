"""Textual front end: the app, its screens and widgets. Never imports gymnasium."""

import os

MAX_FPS = 240
os.environ.setdefault("TEXTUAL_FPS", str(MAX_FPS))
