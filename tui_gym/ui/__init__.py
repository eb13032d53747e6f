"""Textual front end: the app, its screens and widgets. Never imports gymnasium."""
