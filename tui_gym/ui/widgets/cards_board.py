"""`CardsBoard`: a card table that draws the dealer's and the player's hands."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, NamedTuple

from rich.style import Style
from rich.text import Text
from textual.binding import Binding, BindingType

from tui_gym.ui.widgets.board_drawing import stack
from tui_gym.ui.widgets.boards import Board
from tui_gym.ui.widgets.strip_widget import component_classes

SUITS = ("♠", "♥", "♦", "♣")
RED_SUITS = frozenset({"♥", "♦"})
ON_FELT = frozenset({"label", "muted", "total", "bust", "best"})


def card_label(card: int) -> str:
    """'A' for an ace, else the card's value."""
    return "A" if card == 1 else str(card)


class CardSize(NamedTuple):
    """How big a card is drawn: `width` x `height` cells (height 1: a chip of text)."""

    width: int
    height: int


SIZES = (CardSize(7, 5), CardSize(5, 3), CardSize(4, 1))  # large, medium, mini


class CardsBoard(Board):
    """The Blackjack table: the dealer's hand above, the player's below."""

    SCOPED_CSS = False  # unscoped, so that `Screen.compact ...` rules can match
    DEFAULT_CSS = """
    CardsBoard > BoardCanvas { background: $success 12%; }
    CardsBoard > .board-buttons { background: $success 12%; }
    CardsBoard .cards--face { background: #f5f1e6; color: #1b1b1b; }
    CardsBoard .cards--red { background: #f5f1e6; color: #c0282d; }
    CardsBoard .cards--edge { background: #f5f1e6; color: #8d8778; }
    CardsBoard .cards--back { background: #22508f; color: #d9e3f2; }
    CardsBoard .cards--back-fill { background: #22508f; color: #7ea2d6; }
    CardsBoard .cards--label { color: $text; text-style: bold; }
    CardsBoard .cards--muted { color: $text-muted; }
    CardsBoard .cards--total { color: $text; text-style: bold; }
    CardsBoard .cards--bust { color: $text-error; text-style: bold; }
    CardsBoard .cards--best { color: $text-success; text-style: bold; }
    CardsBoard .cards--tag { background: $warning 70%; color: #1b1b1b; text-style: bold; }
    """

    COMPONENT_CLASSES: ClassVar[set[str]] = component_classes(DEFAULT_CSS)

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("h", "act('hit')", "Hit", tooltip="Take another card"),
        Binding("s", "act('stick')", "Stick", tooltip="Keep your hand; the dealer plays"),
        Binding("n,enter", "new_episode", "Deal", key_display="n", tooltip="Deal the next hand"),
    ]

    BUTTONS = (
        ("Hit [dim]h[/]", "act('hit')"), ("Stick [dim]s[/]", "act('stick')"),
        ("Deal [dim]n[/]", "new_episode"),
    )
    BORDER_TITLE = "Table"
    STYLE = "cards"
    RESTART_ANYTIME = False

    # --- what the board says ---------------------------------------------------
    def key_help(self) -> list[tuple[str, str]]:
        return [
            ("h", "hit: take another card"), ("s", "stick: keep your hand, the dealer plays"),
            ("n / enter", "deal the next hand"),
            ("click", "the Hit / Stick / Deal buttons under the table"),
        ]

    prompt = "Hit (h) or stick (s)?"
    over_hint = "This hand is over: press n or Enter (or click Deal) for the next one."
    unfinished_hint = "Finish this hand first: hit (h) or stick (s)."

    def button_enabled(self, action: str) -> bool:
        return self.episode_over if action == "new_episode" else not self.episode_over

    def button_suggested(self, action: str) -> bool:
        return self.episode_over and action == "new_episode"

    # --- drawing ---------------------------------------------------------------
    def _style(self, name: str) -> Style:
        style = super()._style(name)
        if name in ON_FELT:  # text straight on the table: keep the canvas's background
            return Style.from_color(style.color) + style.without_color
        return style

    def _card(
        self, hand: int, position: int, card: int, size: CardSize, face_up: bool
    ) -> list[Text]:
        """The lines of one card, each `size.width` cells wide."""
        inner = size.width - 2
        if face_up:
            # A decorative suit, fixed by the hand, place and card: neighbours always differ.
            rank, suit = card_label(card), SUITS[(3 * position + 2 * card + hand) % len(SUITS)]
            frame, ink = self._style("edge"), self._style("red" if suit in RED_SUITS else "face")
            if size.height == 1:
                return [Text(f"{rank:>2}{suit} ", ink)]
            middle = ([f"{rank:<2}{suit}".ljust(inner)] if size.height == 3
                      else [f"{rank:<{inner}}", f"{suit:^{inner}}", f"{rank:>{inner}}"])
        else:
            frame, ink = self._style("back"), self._style("back-fill")
            if size.height == 1:
                return [Text("░" * size.width, ink)]
            middle = ["░" * inner] * (size.height - 2)
        lines = [Text("╭" + "─" * inner + "╮", frame)]
        for text in middle:
            line = Text("│", frame)
            line.append(text, ink)
            line.append("│", frame)
            lines.append(line)
        lines.append(Text("╰" + "─" * inner + "╯", frame))
        return lines

    def _hand(self, hand: int, cards: Sequence[int], size: CardSize, hidden: int) -> list[Text]:
        """A hand's rows of cards side by side; cards from index `hidden` on lie face down."""
        drawn = [
            self._card(hand, i, card, size, face_up=i < hidden) for i, card in enumerate(cards)
        ]
        return [Text(" ").join(lines[r] for lines in drawn) for r in range(size.height)]

    def _total(self, who: str, cards: Sequence[int]) -> tuple[int, bool]:
        """A hand's total and usable ace, as the scene gives them (sums of the cards else)."""
        total = self.scene.get(f"{who}_total")
        if isinstance(total, int):
            return total, bool(self.scene.get(f"{who}_usable", False))
        return sum(cards), False

    def _label(self, who: str, cards: Sequence[int], hidden: bool = False) -> Text:
        """A hand's owner and total: 'Dealer  showing 10', 'You  21 blackjack!  usable ace '."""
        player = who == "player"
        label = Text(self.player_name if player else "Dealer", self._style("label"))
        if not cards:
            return label
        label.append("  ")
        if hidden:
            label.append("showing ", self._style("muted"))
            label.append(card_label(cards[0]), self._style("total"))
            return label
        total, usable = self._total(who, cards)
        if total > 21:
            label.append(f"{total} bust", self._style("bust"))
        elif total == 21 and player:
            label.append("21" + (" blackjack!" if len(cards) == 2 else ""), self._style("best"))
        else:
            label.append(str(total), self._style("total"))
        if usable and player:
            label.append("  ")
            label.append(" usable ace ", self._style("tag"))
        return label

    def picture(self, width: int, height: int) -> Text:
        player = list(self.scene.get("player", []))
        dealer = list(self.scene.get("dealer", []))
        if not player and not dealer:
            hint = "No cards on the table."
            if self.interactive:
                hint += " Press n to deal."
            return stack([Text(hint, self._style("muted"))], width, height, block=True)
        hidden = not self.reveal and len(dealer) > 1
        dealer_label = self._label("dealer", dealer, hidden)
        player_label = self._label("player", player)
        for size in SIZES:
            dealer_rows = self._hand(0, dealer, size, hidden=1 if hidden else len(dealer))
            player_rows = self._hand(1, player, size, hidden=len(player))
            lines = [dealer_label, *dealer_rows, Text(), player_label, *player_rows]
            if size.height > 1 and len(lines) + 1 <= height:
                lines.insert(len(dealer_rows) + 1, Text())  # a little more air
            fits_width = max(line.cell_len for line in lines) <= width
            if fits_width and len(lines) <= height:
                break
        return stack(lines, width, height, block=True)

