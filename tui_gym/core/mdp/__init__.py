"""Finite MDPs, solved exactly: the ruler every agent on a finite game is measured against.

With an episode limit H a value counts at most H steps and the optimum comes from
backward induction (no fixed policy beats it, so a gap is never negative); with no limit
it is discounted (gamma < 1) or the total of an episode (gamma = 1; minus infinity for a
policy that may never end one).
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
