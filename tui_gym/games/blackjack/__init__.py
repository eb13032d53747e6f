"""Blackjack: the game (`game`), and its exact dynamic programme and finite model (`solver`)."""

from tui_gym.games.blackjack.game import BlackjackGame

__all__ = ["BlackjackGame"]
