"""Blackjack: the game (`game`), its exact dynamic programme (`solver`) and its
batched form for the vector engine (`batched`)."""

from tui_gym.games.blackjack.game import BlackjackGame

__all__ = ["BlackjackGame"]
