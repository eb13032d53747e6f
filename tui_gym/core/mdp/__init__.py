"""Finite MDPs, solved exactly: the ruler every agent on a finite game is measured against.

**The exact value of a policy** is the expected sum of rewards of one episode,
each discounted by gamma to the power of its step (gamma defaults to 1, the
plain return), with the first state drawn from the game's initial distribution
and the episode ending at the first terminal transition or, when the game has
an episode limit H, after H steps, whichever comes first:

- **With a limit H**, the value counts at most H steps, so it is finite for
  every policy, including one that never ends an episode. The optimum is the
  best value any way of playing reaches within those H steps, found by backward
  induction; it may play differently as the limit nears, so no fixed policy,
  greedy or otherwise, beats it, and the exact gap of any policy is never
  negative.
- **With no limit and gamma < 1**, the value is the discounted infinite sum,
  finite for every policy; the optimum is found by policy iteration.
- **With no limit and gamma = 1**, the value is the expected total reward of
  an episode, for a policy that ends episodes with probability 1. A policy
  that may never end one (with positive probability, from the initial
  distribution) is reported as never ending: its value is minus infinity and
  its gap plus infinity. The optimum is the best over the policies that end
  episodes surely (minus infinity if none does; plus infinity, unbounded, if a
  cycle that gains reward can be repeated at will before ending).

The optimal action values `Q*(s, a)` are those of taking `a` in `s` at the
start of an episode (with H steps left) and playing optimally after; a coach
answering mid-episode asks for them with the steps that are left.

Modules, one job each:

- `model`: `FiniteMDP`, dense `[S, A, K]` transition arrays (rewards with noise keep
  their mean and give their deviation); `ModelError`;
- `phases`: `Phases`, a world that changes as it is played, the model of each phase;
- `from_env`: `model_from_env` for envs with a `P` table, or `NotAvailable`;
- `transforms`: the model under `ScaleReward`, `StepPenalty`, `ClipReward`, `TimeLimit`;
- `policy`: deterministic and stochastic policies, `greedy_policy`;
- `evaluation`: `evaluate`, a policy's exact value (`PolicyValue`);
- `optimum`: `solve`, the optimum (`Solution`, with `Q*` and `V*`); `optimal_actions`;
- `gap`: `exact_gap`, a policy's value beside the optimum (`Gap`);
- `ending`: which states a policy (or any policy) ends episodes from;
- `returns`: `return_range`, the lowest and highest return one episode can have;
- `policy_arrays`: `PolicyArrays`, a policy's Bellman expectation, swept synchronously
  or in place;
- `planning`: dynamic programming sweep by sweep (`Planner`: policy evaluation, policy
  iteration, value iteration), with the book's discounted values and no episode limit.
"""

from tui_gym.core.mdp.evaluation import PolicyValue, evaluate
from tui_gym.core.mdp.from_env import NotAvailable, model_from_env
from tui_gym.core.mdp.gap import Gap, exact_gap
from tui_gym.core.mdp.model import FiniteMDP, ModelError
from tui_gym.core.mdp.optimum import Solution, optimal_actions, solve
from tui_gym.core.mdp.phases import Phases
from tui_gym.core.mdp.policy import PolicyError, greedy_policy, policy_matrix
from tui_gym.core.mdp.returns import return_range
from tui_gym.core.mdp.transforms import clip_reward, scale_reward, step_penalty, with_horizon

__all__ = [
    "FiniteMDP",
    "Gap",
    "ModelError",
    "NotAvailable",
    "Phases",
    "PolicyError",
    "PolicyValue",
    "Solution",
    "clip_reward",
    "evaluate",
    "exact_gap",
    "greedy_policy",
    "model_from_env",
    "optimal_actions",
    "policy_matrix",
    "return_range",
    "scale_reward",
    "solve",
    "step_penalty",
    "with_horizon",
]
