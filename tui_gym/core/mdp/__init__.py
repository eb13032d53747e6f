"""Finite MDPs, solved exactly: the ruler every agent on a finite game is measured against.

With an episode limit H a value counts at most H steps (the optimum by backward induction);
with none it is discounted, or with gamma 1 an episode's total (-inf if it may never end).
"""

from tui_gym.core.mdp.evaluation import evaluate, return_range
from tui_gym.core.mdp.from_env import NotAvailable, model_from_env
from tui_gym.core.mdp.model import FiniteMDP, ModelError, Phases, with_horizon
from tui_gym.core.mdp.optimum import (
    TIE_GAMMA,
    Ladder,
    Solution,
    exact_gap,
    gap_of,
    optimal_actions,
    solve,
)
from tui_gym.core.mdp.policy import PolicyError, greedy_policy, policy_matrix

__all__ = [
    "TIE_GAMMA", "FiniteMDP", "Ladder", "ModelError", "NotAvailable", "Phases", "PolicyError",
    "Solution", "evaluate", "exact_gap", "gap_of", "greedy_policy", "model_from_env",
    "optimal_actions", "policy_matrix", "return_range", "solve", "with_horizon",
]
