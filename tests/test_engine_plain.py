"""With `NUMBA_DISABLE_JIT=1` every kernel runs as plain Python: the smallest game's contract
still holds, every learner trains to the very tables it trains to compiled, and every
prediction learner scores the same RMS curves on the random walk, so coverage and a debugger
see the engine as it runs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tui_gym.algorithms import ALGORITHMS
from tui_gym.session.session import Session

from .test_prediction import curves

# One worker runs this module, so the plain Python process below starts once.
pytestmark = pytest.mark.xdist_group("engine_plain")

ROOT = Path(__file__).resolve().parent.parent
EPISODES = 400  # a whole budget: exploration runs from its start to its end
# Prioritized sweeping plans several sweeps per move, each a queue walk in plain Python: a
# shorter whole budget.
BUDGETS = {"prioritized-sweeping": 100}
NAMES = [cls.name for cls in ALGORITHMS]
# One process where every kernel is plain Python: the smallest game's contract (then its
# pytest run's exit code on a line), then every learner trained as `_trained` does, then
# the prediction learners' RMS curves.
PLAIN_RUN = """
import json
import sys
import numba
import numpy as np
import pytest
assert numba.config.DISABLE_JIT
code = pytest.main(["-q", "-n", "0", "-p", "no:cacheprovider", "tests/test_games_contract.py",
                    "-k", "frozenlake and not default_training"])
print("contract exit", int(code), flush=True)
from tests.test_engine_plain import NAMES, _trained
from tests.test_prediction import curves
np.savez(sys.argv[1], **{name: _trained(name) for name in NAMES})
with open(sys.argv[2], "w") as file:
    json.dump(curves(), file)
"""


@pytest.fixture(scope="module")
def plain(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[subprocess.CompletedProcess[str], Path]:
    """The plain Python process's run, and the folder of the tables and curves it wrote."""
    folder = tmp_path_factory.mktemp("plain")
    done = subprocess.run(
        [sys.executable, "-c", PLAIN_RUN, str(folder / "plain.npz"), str(folder / "rms.json")],
        cwd=ROOT, env=_plain_env(), capture_output=True, text=True, timeout=600, check=False,
    )
    return done, folder


def _plain_env() -> dict[str, str]:
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    env.pop("PYTEST_XDIST_WORKER", None)
    return env


def _trained(algorithm: str) -> np.ndarray:
    """The action values of `algorithm` after a whole budget on the smallest game."""
    episodes = BUDGETS.get(algorithm, EPISODES)
    session = Session("frozenlake", seed=0, algorithm=algorithm, hp={"episodes": episodes})
    assert session.training is not None, session.engine_reason  # the compiled loop's model
    session.trainer.run(episodes=episodes)
    assert session.trainer.remaining == 0
    return session.agent.table()[0]


def test_the_smallest_games_contract_holds_with_the_kernels_as_plain_python(plain) -> None:
    # Its default training as plain Python is the compiled one's (below), which
    # tests/test_contract_learners.py::test_each_algorithm_meets_the_games_bound_with_its_defaults
    # checks.
    done, _ = plain
    assert "\ncontract exit 0\n" in done.stdout, (
        done.stdout[-3000:] + done.stderr[-2000:])
    assert " passed" in done.stdout and "failed" not in done.stdout


def test_every_learner_trains_to_the_same_tables_as_plain_python(plain) -> None:
    done, folder = plain
    assert done.returncode == 0, done.stderr[-3000:]
    plain_tables = np.load(folder / "plain.npz")
    for name in NAMES:
        compiled = _trained(name)
        assert compiled.any(), f"{name}: a budget that changes nothing proves nothing"
        assert np.array_equal(plain_tables[name], compiled), (
            name, np.abs(plain_tables[name] - compiled).max())


def test_the_compiled_rules_and_the_plain_python_ones_give_the_same_runs(plain) -> None:
    done, folder = plain
    assert done.returncode == 0, done.stderr[-3000:]
    plain_curves = json.loads((folder / "rms.json").read_text())
    compiled = curves()
    assert plain_curves.keys() == compiled.keys()
    for name, curve in compiled.items():
        assert plain_curves[name] == pytest.approx(curve, abs=1e-12), name
