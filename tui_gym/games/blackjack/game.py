"""Blackjack: Gymnasium's `Blackjack-v1` as the app sees it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import NotAvailable, greedy_policy, return_range
from tui_gym.core.params import Param
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.games.base import (
    EXACT,
    TIED,
    Advice,
    Bound,
    EvalOutcome,
    FixedBound,
    Game,
    HeatmapLayout,
    Narrator,
    Optimum,
    Oracle,
    ReferenceMetrics,
    Scope,
    StateSpace,
    TrainingModel,
    greedy_panel,
)
from tui_gym.games.blackjack.solver import (
    BASE_STATES,
    DEALERS,
    LONGEST_HAND,
    N_BASE,
    POLICY_SHAPE,
    BlackjackRules,
    base_state,
    blackjack_model,
    mixed_policy_value,
    observation_rows,
    optimal_action_values,
    optimal_policy,
    optimal_value,
)
from tui_gym.games.words import format_reward, plural, unwrapped_note

if TYPE_CHECKING:
    from tui_gym.games.planning import PlanModel
    from tui_gym.session.play import PlayStep

__all__ = ["CHART_SUMS", "DEALER_CARDS", "DEALER_LABELS", "BlackjackGame", "card_label",
           "hand_value"]

CHART_SUMS = tuple(range(21, 11, -1))  # rows of the chart, top to bottom
DEALER_CARDS = tuple(range(1, 11))  # columns: A, 2 .. 10
DEALER_LABELS = ("A", "2", "3", "4", "5", "6", "7", "8", "9", "10")
ACTION_LETTERS = ("S", "H")
TRAINED_GAP = 0.005  # what the default training reaches (see the README)
ON_POLICY = {"epsilon_final": 0.0, "epsilon_decay_fraction": 0.3}  # the on-policy learners'
MULTI_STEP = {**ON_POLICY, "learning_rate": 0.005, "episodes": 1_000_000}


_BASE_INDEX = tuple(np.array(o) for o in zip(*BASE_STATES, strict=True))  # in a (32, 11, 2) table


def hand_value(cards: list[int]) -> tuple[int, bool]:
    """The hand's total and whether it holds a usable ace (an ace counted as 11)."""
    total = sum(cards)
    usable = 1 in cards and total + 10 <= 21
    return (total + 10 if usable else total), usable


def card_label(card: int) -> str:
    """'A' for an ace, else the card's value."""
    return "A" if card == 1 else str(card)


class BlackjackStates(StateSpace):
    """Decision states `(player sum, dealer card, usable ace)`; the hands as the scene."""

    def base_observations(self, kwargs: Mapping[str, Any]) -> list[Any]:
        return list(BASE_STATES)

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        player, dealer, usable = (int(v) for v in observation)
        ace = "usable ace" if usable else "no usable ace"
        return f"sum {player} vs dealer {card_label(dealer)}, {ace}"

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        """The hands: `player` and `dealer` card lists (1 = ace, 10 = ten or face), and
        their totals (`player_usable`: the player's ace counts 11)."""
        player = [int(c) for c in getattr(game_env, "player", [])]
        dealer = [int(c) for c in getattr(game_env, "dealer", [])]
        player_total, usable = hand_value(player)
        return {
            "player": player, "dealer": dealer, "player_total": player_total,
            "player_usable": usable, "dealer_total": hand_value(dealer)[0],
        }

    def text(self, env: Any, reveal: bool = True, before: Mapping[str, Any] | None = None) -> str:
        """Both hands as text; the dealer's hole card shows only with `reveal`."""
        hands = self.scene(env)
        dealer = hands.get("dealer", [])
        shown = [card_label(c) for c in (dealer if reveal else dealer[:1])]
        if not reveal and len(dealer) > 1:
            shown.append("??")
        player = " ".join(card_label(c) for c in hands.get("player", []))
        return f"dealer: {' '.join(shown)}\nplayer: {player}"


class BlackjackOracle(Oracle):
    """The exact figures of the infinite-deck dynamic programme."""

    def rules(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> BlackjackRules:
        """The rules the exact figures use: the wrapped game's where `scope` is exact."""
        rules = BlackjackRules.from_env_kwargs(kwargs)
        if changes.changes_rewards and self.scope(kwargs, changes).exact:
            rules = rules.with_rewards(changes.reward)
        return rules

    def scope(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Scope:
        """Exact for reward wrappers and a TimeLimit that never cuts a hand short."""
        others = list(changes.others)
        if changes.time_limit is not None and changes.time_limit < LONGEST_HAND:
            others.append(f"TimeLimit(max_episode_steps={changes.time_limit})")
        if others:
            return Scope(False, unwrapped_note(others))
        if changes.changes_rewards:
            return Scope(True, f"exact with {changes.reward_names()}")
        return EXACT

    def hit_probability(self, q: np.ndarray) -> np.ndarray:
        """The greedy policy of `q` (rows = base states) as a (32, 11, 2) table of the
        chance to hit: 0 or 1, or 0.5 where the two actions tie (the agent picks at random)."""
        table = np.zeros(POLICY_SHAPE, dtype=np.float64)
        table[_BASE_INDEX] = greedy_policy(q)[:, 1]
        return table

    def reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        if np.shape(q) != (N_BASE, 2):
            return NotAvailable(f"a table of shape {np.shape(q)} does not fit Blackjack")
        rules = self.rules(kwargs, changes)
        exact = mixed_policy_value(self.hit_probability(q), rules)  # as the agent plays it
        best = optimal_value(rules)
        return ReferenceMetrics(
            figures={"exact_value": exact, "optimal_value": best, "gap": best - exact},
            summary=f"exact value {exact:+.4f}  optimum {best:+.4f}  gap {best - exact:.4f}",
            scope=self.scope(kwargs, changes),
        )

    def agent_figures(
        self, q: np.ndarray | None, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> dict[str, float]:
        """`exact_value` of the greedy policy (as `reference` has it) and `optimal_value`."""
        if q is None:
            return {"optimal_value": optimal_value(self.rules(kwargs, changes))}
        reference = self.reference(q, kwargs, changes)
        return {} if isinstance(reference, NotAvailable) else dict(reference.figures)

    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        hands = self.game.states.scene(env)
        player, dealer = hands.get("player", []), hands.get("dealer", [])
        if not player or not dealer:
            return Advice((), None, "no hand dealt")
        total, usable = hand_value(player)
        if total > 21:
            return Advice((), None, "bust: no decision left")
        changes = GameChanges.of(env)
        scope = self.scope(kwargs, changes)
        soft_21: Literal["natural", "drawn"] = (
            "natural" if len(player) == 2 and total == 21 else "drawn"
        )
        q = optimal_action_values(self.rules(kwargs, changes), soft_21=soft_21)[
            total, dealer[0], int(usable)
        ]
        values = {a: float(q[a]) for a in range(2)}
        best = max(values.values())
        optimal = tuple(a for a, v in values.items() if v >= best - 1e-12)
        names = " or ".join(self.game.action_names[a] for a in optimal)
        expected = f"stick {values[0]:+.3f}, hit {values[1]:+.3f} expected"
        if not scope.exact:
            return Advice((), None, f"the unwrapped game's optimum: {names}  ({expected} "
                          f"there; {scope.note.removeprefix('figures of the unwrapped game: ')})",
                          unwrapped_optimal=optimal)
        return Advice(optimal, values, f"optimal: {names}  ({expected})")

    def optimal_marks(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> np.ndarray:
        best = optimal_policy(self.rules(kwargs, changes))[_BASE_INDEX]
        marks = np.zeros((len(best), 2), dtype=bool)
        marks[np.arange(len(best)), best] = True
        return marks

    def optimum(self, kwargs: Mapping[str, Any]) -> Optimum:
        rules = BlackjackRules.from_env_kwargs(kwargs)
        q = optimal_action_values(rules, soft_21="drawn")[_BASE_INDEX]
        return Optimum(
            value=optimal_value(rules),
            summary="the exact expected return per hand of the optimal strategy", q=q,
            marks=self.optimal_marks(kwargs),
        )

    def bound(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Bound:
        return Bound("gap", TRAINED_GAP, f"gap <= {TRAINED_GAP}")

    def return_range(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> tuple[float, float] | NotAvailable:
        scope = self.scope(kwargs, changes)
        if not scope.exact:
            return NotAvailable(scope.note)
        return return_range(blackjack_model(self.rules(kwargs, changes)))

    def fixed_policy_bound(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> FixedBound:
        value = optimal_value(self.rules(kwargs, changes))
        return FixedBound(value, value)  # no episode limit: a fixed policy is optimal


class BlackjackNarrator(Narrator):
    """Hands won, pushed and lost, in the words of a card table."""

    agreement_words = "optimal decisions"
    value_places = 4

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        """'You win +1', 'Dealer wins −1 (you bust)', 'Push 0' from the final reward."""
        if not last.terminated:
            steps, total = plural(last.steps, "move"), format_reward(last.episode_return)
            return f"Hand cut short by the time limit after {steps}, return {total}"
        player, _ = hand_value(list(scene.get("player", [])))
        dealer, _ = hand_value(list(scene.get("dealer", [])))
        reward = format_reward(last.reward)
        if last.reward > 0:
            if len(scene.get("player", [])) == 2 and player == 21:
                return f"You win {reward} (blackjack!)"
            if dealer > 21:
                return f"You win {reward} (the dealer busts with {dealer})"
            return f"You win {reward} (your {player} beats the dealer's {dealer})"
        if last.reward < 0:
            if player > 21:
                return f"Dealer wins {reward} (you bust with {player})"
            return f"Dealer wins {reward} (the dealer's {dealer} beats your {player})"
        return f"Push {reward} (both have {player})"

    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        r = np.asarray(returns, dtype=np.float64)
        n = max(1, len(r))
        shares = {"win_rate": r > 0, "draw_rate": r == 0, "loss_rate": r < 0}
        return EvalOutcome({name: float(np.count_nonzero(hit)) / n for name, hit in shares.items()})


class BlackjackLayout(HeatmapLayout):
    """The two halves of a basic-strategy chart: with and without a usable ace."""

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        if np.shape(q) != (N_BASE, 2):
            return []
        has_marks = isinstance(marks, np.ndarray)

        def chart(usable: int, title: str) -> Heatmap:
            rows = np.array([[base_state(player, dealer, usable) for dealer in DEALER_CARDS]
                             for player in CHART_SUMS])  # the Q-table row of each chart cell
            return greedy_panel(
                f"Q-values, {title}",
                f"rows: player sum  cols: dealer card  H hit  S stick  {TIED} tie  * not optimal",
                tuple(str(s) for s in CHART_SUMS), DEALER_LABELS, lambda r, c: None,
                lambda r, c: q[rows[r, c]], ACTION_LETTERS.__getitem__,
                lambda r, c, action: has_marks and not marks[rows[r, c], action],
            )

        return [chart(1, "usable ace"), chart(0, "no usable ace")]


class BlackjackGame(Game):
    """Hit or stick against a dealer who stands on 17."""

    name = "blackjack"
    title = "Blackjack"
    env_id = "Blackjack-v1"
    key = "b"
    description = "Hit or stick; beat the dealer without going over 21 (infinite deck)."
    teaches = "acting on probabilities: the same hand calls for a hit or a stick by the dealer"
    action_names = ("stick", "hit")
    params = (
        Param("natural", bool, False, help="a natural blackjack pays 1.5"),
        Param("sab", bool, False, help="Sutton & Barto's rules"),
    )
    board = "cards"
    episode_noun = "hand"
    bench_kwargs: dict[str, Any] | None = {}
    bench_gap = 0.002
    # On-policy learners stop exploring and step larger; multi-step ones step smaller over more
    # hands; Dyna's one-outcome model misleads here, so one small planning step (see the README).
    hyperparameters = {
        **dict.fromkeys(("sarsa", "expected-sarsa"), {**ON_POLICY, "learning_rate": 0.01,
                                                      "episodes": 500_000}),
        "monte-carlo": {"learning_rate": 0.003, "epsilon_final": 0.0,
                        "epsilon_decay_fraction": 0.5, "episodes": 1_500_000},
        **dict.fromkeys(("dyna-q", "dyna-q-plus"), {"planning_steps": 1, "learning_rate": 0.0003,
                                                    "episodes": 700_000}),
        "n-step-sarsa": {"n": 2, **MULTI_STEP}, "sarsa-lambda": MULTI_STEP,
    }
    lessons = {
        "prioritized-sweeping": "prioritized sweeping's model keeps the last card each move "
        "drew, and its queue updates first the pairs whose last draw surprised most: the "
        "surprising cards weigh more than their chance, and the values drift from the optimum",
    }

    states_type = BlackjackStates
    oracle_type = BlackjackOracle
    narrator_type = BlackjackNarrator
    layout_type = BlackjackLayout

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel:
        """The hands as a finite model (`solver.blackjack_model`); a natural plays as a soft 21."""
        from tui_gym.games.planning import PlanModel

        base_of = np.r_[np.arange(N_BASE), base_state(21, 1, 1) + np.arange(DEALERS)]
        model = blackjack_model(BlackjackRules.from_env_kwargs(kwargs))
        return PlanModel(model, 1.0, None, base_of=base_of, shown=np.arange(N_BASE))

    def training_model(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> TrainingModel | NotAvailable:
        if changes.others:
            return NotAvailable(unwrapped_note(changes.others))
        rules = BlackjackRules.from_env_kwargs(kwargs)
        if changes.changes_rewards:
            rules = rules.with_rewards(changes.reward)
        model = blackjack_model(rules)
        if changes.time_limit is not None:
            model = model.replace(horizon=changes.time_limit)
        return TrainingModel(model, observation_rows())
