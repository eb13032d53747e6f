"""Tabular learners, one file each, and the `ALGORITHMS` registry.

After a truncation every rule bootstraps from the next state: the time limit is not part
of the game.
"""

from __future__ import annotations

from tui_gym.algorithms.base import CellUpdate, Learner, LearnerState, UpdateRecord
from tui_gym.algorithms.double_q import DoubleQLearning
from tui_gym.algorithms.dyna_q import DynaQ
from tui_gym.algorithms.dyna_q_plus import DynaQPlus
from tui_gym.algorithms.expected_sarsa import ExpectedSarsa
from tui_gym.algorithms.mc_prediction import MonteCarloPrediction
from tui_gym.algorithms.monte_carlo import MonteCarlo
from tui_gym.algorithms.nstep_sarsa import NStepSarsa
from tui_gym.algorithms.nstep_td import NStepTD
from tui_gym.algorithms.offline_lambda import OfflineLambdaReturn
from tui_gym.algorithms.prediction import Predictor
from tui_gym.algorithms.prioritized_sweeping import PrioritizedSweeping
from tui_gym.algorithms.q_lambda import WatkinsQLambda
from tui_gym.algorithms.qlearning import QLearning
from tui_gym.algorithms.sarsa import Sarsa
from tui_gym.algorithms.sarsa_lambda import SarsaLambda
from tui_gym.algorithms.settings import COMMON_PARAMS, Field, Settings
from tui_gym.algorithms.td0 import TD0
from tui_gym.algorithms.td_lambda import TDLambda

__all__ = [
    "ALGORITHMS", "ALL_PARAMS", "COMMON_PARAMS", "DEFAULT_ALGORITHM", "CellUpdate",
    "DoubleQLearning", "DynaQ", "DynaQPlus", "ExpectedSarsa", "Field", "Learner", "LearnerState",
    "MonteCarlo", "NStepSarsa", "PrioritizedSweeping", "MonteCarloPrediction", "NStepTD",
    "OfflineLambdaReturn", "Predictor", "QLearning", "Sarsa", "SarsaLambda", "Settings", "TD0",
    "TDLambda", "UpdateRecord", "WatkinsQLambda", "algorithm",
]

ALGORITHMS: tuple[type[Learner], ...] = (
    QLearning, Sarsa, ExpectedSarsa, DoubleQLearning, MonteCarlo, DynaQ, NStepSarsa, SarsaLambda,
    WatkinsQLambda, DynaQPlus, PrioritizedSweeping, TD0, MonteCarloPrediction, NStepTD, TDLambda,
    OfflineLambdaReturn,
)

DEFAULT_ALGORITHM = QLearning.name

_BY_NAME = {cls.name: cls for cls in ALGORITHMS}


def _union() -> tuple[Field, ...]:
    seen: dict[str, Field] = {}
    for cls in ALGORITHMS:
        for field in cls.params:
            seen.setdefault(field.name, field)
    return tuple(seen.values())


ALL_PARAMS: tuple[Field, ...] = _union()
"""Every hyperparameter of any algorithm, once each (the common ones first)."""


def algorithm(name: str) -> type[Learner]:
    """The learner class registered as `name` (case and `_`/`-` ignored); ValueError naming
    the registered ones."""
    wanted = str(name).strip().lower().replace("_", "-")
    found = _BY_NAME.get(wanted)
    if found is None:
        raise ValueError(f"unknown algorithm {name!r}; choose one of {', '.join(_BY_NAME)}")
    return found
