"""Exact reference answers the app shows beside a learning agent.

- `blackjack`: exact DP for Gymnasium's ``Blackjack-v1``: the value of any
  deterministic policy, Q*, the optimal policy and its value, per reward rules.
- `gridworld`: GridWorld shortest paths, the share of start placements from
  which a policy takes one, and the steps a policy takes over the fewest.
"""

from tui_gym.core.reference.blackjack import (
    DECISION_MASK,
    DEFAULT_RULES,
    HIT,
    POLICY_SHAPE,
    STICK,
    BlackjackRules,
    optimal_action_values,
    optimal_policy,
    optimal_value,
    policy_from_function,
    policy_value,
)
from tui_gym.core.reference.gridworld import (
    GRID_ACTION_DELTAS,
    all_pairs,
    optimal_actions,
    optimal_pair_fraction,
    policy_steps_over_optimal,
    shortest_path_length,
    shortest_path_policy,
)

__all__ = [
    "DECISION_MASK",
    "DEFAULT_RULES",
    "GRID_ACTION_DELTAS",
    "HIT",
    "POLICY_SHAPE",
    "STICK",
    "BlackjackRules",
    "all_pairs",
    "optimal_action_values",
    "optimal_actions",
    "optimal_pair_fraction",
    "optimal_policy",
    "optimal_value",
    "policy_from_function",
    "policy_steps_over_optimal",
    "policy_value",
    "shortest_path_length",
    "shortest_path_policy",
]
