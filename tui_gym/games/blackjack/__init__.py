"""Blackjack: the game (`game`), its exact dynamic programme (`solver`) and its
finite model over the observations (`model`)."""

from tui_gym.games.blackjack.game import BlackjackGame

__all__ = ["BlackjackGame"]
