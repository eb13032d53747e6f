"""What one `tui-gym bench` run found: every stage's result, and where a stage failed."""

from __future__ import annotations

from dataclasses import dataclass, field

from tui_gym.bench.compiling import CompileResult
from tui_gym.bench.defaults import DefaultsResult
from tui_gym.bench.dp import DPResult
from tui_gym.bench.gap import GapResult
from tui_gym.bench.history import HistoryResult
from tui_gym.bench.learners import PlanningResult
from tui_gym.bench.live import DEFAULT_RUNNER, LiveResult
from tui_gym.bench.map_edit import MapEditResult
from tui_gym.bench.memory import MemoryResult
from tui_gym.bench.programs import ProgramsResult
from tui_gym.bench.seeds import SeedsSpeed
from tui_gym.bench.speed import Speed
from tui_gym.bench.startup import StartupResult
from tui_gym.bench.tasks import TasksResult


@dataclass(frozen=True)
class MachineInfo:
    """The machine the figures were measured on, and how busy it was."""

    cpus: int | None
    load_before: tuple[float, float, float] | None
    load_after: tuple[float, float, float] | None


@dataclass(frozen=True)
class BenchResults:
    """Every stage's result (None when it failed: `errors` says why)."""

    quick: bool
    seconds: float  # the whole run
    machine: MachineInfo
    compile: CompileResult | None = None
    speed: tuple[Speed, ...] | None = None  # every (game, algorithm) against the tutorial
    gap: dict[str, GapResult] = field(default_factory=dict)  # by game name
    live: dict[str, LiveResult] = field(default_factory=dict)  # by runner
    memory: MemoryResult | None = None
    startup: StartupResult | None = None
    planning: PlanningResult | None = None  # Dyna-Q against Q-learning, real episodes
    programs: ProgramsResult | None = None
    map_edit: tuple[MapEditResult, ...] | None = None  # edit to new optimum, per grid game
    history: HistoryResult | None = None  # the run history's overhead and size
    seeds: SeedsSpeed | None = None  # `compare` against the same learners in a loop
    defaults: tuple[DefaultsResult, ...] | None = None  # the share of seeds at the bound
    dp: DPResult | None = None  # planning: sweeps, Jack's car rental, the Plan view
    tasks: TasksResult | None = None  # the task split's overhead, a Dask cluster's share
    errors: dict[str, str] = field(default_factory=dict)  # stage -> what went wrong
    default_runner: str = DEFAULT_RUNNER

    def live_for(self, runner: str) -> LiveResult | None:
        """A runner's live figures, or None when it has none (not run, or failed)."""
        result = self.live.get(runner)
        return result if result is not None and result.repeats else None
