"""GridWorld: our `tui_gym/GridWorld-v0` as the app sees it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import NotAvailable, evaluate, gap_of, greedy_policy, return_range
from tui_gym.core.params import Param
from tui_gym.core.wrappers.changes import NO_CHANGES, GameChanges
from tui_gym.envs import GRIDWORLD_MAX_STEPS
from tui_gym.envs.gridworld import Walls, cell_distances, cell_moves, check_walls
from tui_gym.games.base import (
    EXACT,
    TIED,
    Advice,
    Bound,
    EvalOutcome,
    Game,
    HeatmapLayout,
    Optimum,
    Oracle,
    ReachNarrator,
    ReferenceMetrics,
    Scope,
    StateSpace,
    TallyWord,
    TrainingModel,
    greedy_panel,
    numbered,
)
from tui_gym.games.gridworld.paths import (
    fewest_share,
    gridworld_model,
    gridworld_optimum,
    path_figures,
    placements,
    shortest_marks,
    shortest_path_optimum,
)
from tui_gym.games.maps import LAYOUT, GridMap, MapError, format_map, layout_map, read_layout
from tui_gym.games.planning import PlanModel
from tui_gym.games.words import (
    ScoreRow,
    agreement_summary,
    format_reward,
    join_parts,
    plural,
    unwrapped_note,
    watched_row,
)

if TYPE_CHECKING:
    from tui_gym.session.play import PlayStep, Scorecard

__all__ = ["GridWorldGame"]

ARROWS = ("→", "↑", "←", "↓")
MIN_SIZE, MAX_SIZE = 2, 12
AGREEMENT = "moves on a shortest path"  # how a scoreboard words moves that match the optimum
WALL = "█"  # a heatmap cell that is a wall
TRAINED_SHARE = 0.95  # what the default training reaches (see the README)


def _size(kwargs: Mapping[str, Any]) -> int:
    return int(kwargs.get("size", 5))


def _walls(kwargs: Mapping[str, Any]) -> Walls:
    """The walls as (x, y) cells (none without a layout)."""
    grid_map = layout_map(kwargs)
    return () if grid_map is None else grid_map.walls_xy()


def _steps_between(size: int, walls: Walls, a: Any, b: Any) -> int:
    """The fewest moves from cell a to cell b, (x, y) each (-1 when walled off)."""
    (ax, ay), (bx, by) = (int(v) for v in a), (int(v) for v in b)
    return int(cell_distances(size, walls)[ax * size + ay, bx * size + by])


def _optimal_from(size: int, walls: Walls, agent: Any, target: Any) -> tuple[int, ...]:
    """The actions that start a shortest path from agent to target."""
    ax, ay = (int(v) for v in agent)
    tx, ty = (int(v) for v in target)
    cells = size * size
    row = shortest_marks(size, walls)[(ax * size + ay) * cells + tx * size + ty]
    return tuple(int(a) for a in np.flatnonzero(row))


def _shortest_pays(kwargs: Mapping[str, Any], changes: GameChanges) -> bool:
    """Whether a shortest path is optimal with these rewards: reaching the target
    pays, and no other step does, nor pays more farther from the target."""
    size = _size(kwargs)
    goal = changes.reward(float(kwargs.get("reward_scale", 1.0)), 0.0)
    miss = -float(kwargs.get("step_penalty", 0.0))
    farthest = max(2 * size - 2, int(cell_distances(size, _walls(kwargs)).max()))
    others = [changes.reward(miss, d) for d in range(1, farthest + 1)]
    never_pays = all(r <= 0.0 for r in others)
    farther_no_better = all(b <= a for a, b in zip(others, others[1:], strict=False))
    return goal > 0.0 and never_pays and farther_no_better


def _model_args(kwargs: Mapping[str, Any], changes: GameChanges) -> tuple[Any, ...]:
    """`gridworld_model`'s arguments for the game's arguments and the wrappers' changes."""
    return (_size(kwargs), float(kwargs.get("reward_scale", 1.0)),
            float(kwargs.get("step_penalty", 0.0)), changes, _walls(kwargs))


def _distance(scene: Mapping[str, Any]) -> int:
    """Steps from the scene's agent to its target (0 when either is missing)."""
    agent, target = scene.get("agent"), scene.get("target")
    if agent is None or target is None:
        return 0
    walls = tuple((int(x), int(y)) for x, y in scene.get("walls", ()))
    return _steps_between(int(scene.get("size", 0)), walls, agent, target)


class GridWorldStates(StateSpace):
    """Every (agent, target) placement; the grid as the scene."""

    def base_observations(self, kwargs: Mapping[str, Any]) -> list[Any]:
        return [{"agent": row[:2].copy(), "target": row[2:].copy()}
                for row in np.indices((_size(kwargs),) * 4, dtype=np.int64).reshape(4, -1).T]

    def describe_state(self, observation: Any, kwargs: Mapping[str, Any]) -> str:
        ax, ay = (int(v) for v in observation["agent"])
        tx, ty = (int(v) for v in observation["target"])
        dist = _steps_between(_size(kwargs), _walls(kwargs), (ax, ay), (tx, ty))
        text = "walled off" if dist < 0 else str(dist)
        return f"agent ({ax}, {ay})  target ({tx}, {ty})  distance {text}"

    def read_scene(self, game_env: Any, before: Mapping[str, Any]) -> dict[str, Any]:
        """The grid: `size`, `agent` and `target` positions as (x, y), and its `walls`."""
        try:
            agent, target = game_env.agent_position, game_env.target_position
        except AttributeError:  # before the first reset
            agent = target = None
        walls = [list(w) for w in getattr(game_env, "walls", ())]
        return {"size": int(game_env.size), "agent": agent, "target": target, "walls": walls}


class GridWorldOracle(Oracle):
    """Shortest paths: exact while the rewards keep one optimal."""

    def scope(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Scope:
        """Exact while the rewards keep a shortest path optimal (the module docstring)."""
        if changes.others:
            return Scope(False, unwrapped_note(changes.others))
        if _shortest_pays(kwargs, changes):
            return EXACT
        if changes.changes_rewards and _shortest_pays(kwargs, NO_CHANGES):
            return Scope(False, f"figures of the unwrapped game: with {changes.reward_names()} "
                         "a shortest path need not pay best")
        return Scope(False, "shortest-path figures: with these rewards a shortest path "
                     "need not pay best")

    def return_range(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> tuple[float, float] | NotAvailable:
        if changes.others:
            return NotAvailable(unwrapped_note(changes.others))
        return return_range(gridworld_model(*_model_args(kwargs, changes)))

    def reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        size = _size(kwargs)
        if np.shape(q) != (size**4, 4):
            return NotAvailable(f"a table of shape {np.shape(q)} does not fit a {size}x{size} grid")
        frac = fewest_share(size, _walls(kwargs), greedy_policy(q))
        return ReferenceMetrics(
            figures={"optimal_pair_fraction": frac},
            summary=f"{frac:.1%} of (agent, target) pairs solved in the fewest steps",
            scope=self.scope(kwargs, changes),
        )

    def evaluation_reference(
        self, q: np.ndarray, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> ReferenceMetrics | NotAvailable:
        """The shortest-path figures and the greedy policy's exact expected return on the
        model (a running view asks only for the first: the model has size**4 states)."""
        reference = self.reference(q, kwargs, changes)
        if isinstance(reference, NotAvailable):
            return reference
        scope = reference.scope
        if changes.changes_rewards and not changes.others and not scope.exact:
            scope = Scope(False, f"{scope.note}; the exact value and gap are with "
                          f"{changes.reward_names()}")
        # The model as the wrappers make it; the unwrapped game's when they change its dynamics.
        args = _model_args(kwargs, GameChanges(time_limit=changes.time_limit)
                           if changes.others else changes)
        value = evaluate(gridworld_model(*args), greedy_policy(q)).value
        best = gridworld_optimum(*args).value
        figures = {**reference.figures, "exact_value": value, "optimal_value": best,
                   "gap": gap_of(best, value)}
        return ReferenceMetrics(figures, reference.summary, scope)

    def agent_figures(
        self, q: np.ndarray | None, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> dict[str, float]:
        """Exact over every placement (ties broken at random, within the time limit): the greedy
        policy's `solved_fraction` and mean `steps_over_optimal` where it reaches the target."""
        size = _size(kwargs)
        if q is None or np.shape(q) != (size**4, 4):
            return {}
        _, extra, solved = path_figures(size, _walls(kwargs), greedy_policy(q),
                                          changes.time_limit)
        return {"steps_over_optimal": extra, "solved_fraction": solved}

    def advice(self, env: Any, kwargs: Mapping[str, Any]) -> Advice:
        scene = self.game.states.scene(env)
        agent, target = scene.get("agent"), scene.get("target")
        if agent is None or target is None:
            return Advice((), None, "no episode running")
        size, walls = _size(kwargs), _walls(kwargs)
        steps = _steps_between(size, walls, agent, target)
        if steps < 0:
            return Advice((), None, "the walls leave no way to the target")
        optimal = _optimal_from(size, walls, agent, target)
        if not optimal:
            return Advice((), None, "at the target")
        names = " or ".join(self.game.action_names[a] for a in optimal)
        scope = self.scope(kwargs, GameChanges.of(env))
        if not scope.exact:
            return Advice((), None, f"shortest path: {names}  ({plural(steps, 'step')} to go; "
                          f"{scope.note.split(': ', 1)[-1]})", unwrapped_optimal=optimal)
        return Advice(optimal, None, f"optimal: {names}  ({plural(steps, 'step')} to go)")

    def optimal_marks(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> np.ndarray:
        return shortest_marks(_size(kwargs), _walls(kwargs))

    def bound(self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES) -> Bound:
        return Bound("optimal_pair_fraction", TRAINED_SHARE,
                     f"{TRAINED_SHARE:.0%} of placements solved in the fewest steps",
                     at_least=True)

    def optimum(self, kwargs: Mapping[str, Any]) -> Optimum:
        """The optimum's exact return per episode, values and shortest-path moves per placement,
        and `optimal_mean_steps`: the mean fewest steps over the random starts."""
        size, walls = _size(kwargs), _walls(kwargs)
        rewards = float(kwargs.get("reward_scale", 1.0)), float(kwargs.get("step_penalty", 0.0))
        found = shortest_path_optimum(size, *rewards, GRIDWORLD_MAX_STEPS, walls)
        if found is None:  # a shortest path need not pay: solve the model
            solution = gridworld_optimum(
                size, *rewards, GameChanges(time_limit=GRIDWORLD_MAX_STEPS), walls
            )
            found = solution.q, solution.value
        optimal_q, value = found
        valid = placements(size, walls)  # the mean fewest steps over them (NaN: there are none)
        mean_steps = float(cell_distances(size, walls)[valid].mean() if valid.any() else np.nan)
        if walls:
            route = f"{size}x{size} with {len(walls)} wall cells: the optimal policy walks a " \
                "shortest way round the walls"
        else:
            route = f"{size}x{size}: the optimal policy walks any shortest path"
        # On the target the episode is over: every move is as good, and worth nothing more.
        over = np.eye(size * size, dtype=bool).reshape(-1)
        q, marks = optimal_q.copy(), self.optimal_marks(kwargs).copy()
        q[over], marks[over] = 0.0, True
        return Optimum(
            value=value,
            summary=f"{route}, {mean_steps:.5g} steps on average over the random starts; "
            "the value is its exact expected return per episode",
            q=q,
            marks=marks,
            figures={"optimal_mean_steps": mean_steps},
        )


class GridWorldNarrator(ReachNarrator):
    """Steps taken against the fewest; reached or timed out."""

    agreement_words = AGREEMENT
    tally_words = (TallyWord("reached", "good"), TallyWord("timed out", "bad"))

    def outcome_text(
        self, last: PlayStep, first_info: Mapping[str, Any], scene: Mapping[str, Any]
    ) -> str:
        """'Reached the target in 7 steps (optimal 7)' or 'Truncated by the time limit ...'."""
        steps, total = plural(last.steps, "step"), format_reward(last.episode_return)
        if last.terminated:
            optimal = int(first_info.get("distance", 0))
            extra = last.steps - optimal
            verdict = "a shortest path" if extra <= 0 else f"{extra} more than needed"
            return f"Reached the target in {steps} (optimal {optimal}), {verdict}; return {total}"
        return f"Truncated by the time limit after {steps}, target not reached, return {total}"

    def progress_text(self, last: PlayStep, first_info: Mapping[str, Any]) -> str:
        optimal = int(first_info.get("distance", 0))
        return f"{plural(last.steps, 'step')} taken, optimal {optimal}"

    def coach_text(
        self, before: Advice, action: int, scene_before: Mapping[str, Any],
        scene_after: Mapping[str, Any],
    ) -> str:
        """'✓ right is on a shortest path (3 steps to go)' or
        '✗ left is off every shortest path (now 5 steps away, was 4)'."""
        if not before.optimal:
            return ""
        names = self.game.action_names
        name = names[action] if 0 <= action < len(names) else str(action)
        was, now = _distance(scene_before), _distance(scene_after)
        if action in before.optimal:
            to_go = f"{plural(now, 'step')} to go" if now else "target reached"
            return f"✓ {name} is on a shortest path ({to_go})"
        return f"✗ {name} is off every shortest path (now {plural(now, 'step')} away, was {was})"

    def episode_figures(self, last: PlayStep, first_info: Mapping[str, Any]) -> dict[str, float]:
        """`steps_over_optimal` of an episode that reached the target."""
        if not last.terminated or "distance" not in first_info:
            return {}
        return {"steps_over_optimal": float(last.steps - int(first_info["distance"]))}

    def scoreboard(
        self, you: Scorecard, figures: Mapping[str, float] | None, watched: Scorecard | None = None,
        agent_note: str = "", scope: Scope = EXACT,
    ) -> list[ScoreRow]:
        """Steps over optimal: yours over the episodes you finished, the agent's exactly."""
        figures = figures or {}
        reached = you.figure_count("steps_over_optimal")
        mean = you.figure_mean("steps_over_optimal")
        if mean is None:
            mine, mine_short = "no episode reached the target yet", "no target reached yet"
        else:
            mine = f"{mean:.2f} steps over optimal (mean of {plural(reached, 'episode')} reached)"
            mine_short = f"{mean:.2f} extra steps ({reached} reached)"
        rows = [
            ScoreRow(
                "You", join_parts(mine, agreement_summary(you, AGREEMENT)),
                join_parts(mine_short, agreement_summary(you, short=True)),
            )
        ]
        solved = figures.get("solved_fraction")
        if solved is None:
            rows.append(ScoreRow("Agent", agent_note or "no exact figures", "–"))
        elif solved == 0:
            text = "its greedy policy reaches the target from no placement yet (exact)"
            rows.append(ScoreRow("Agent", text, "reaches no target yet"))
        else:
            extra = figures["steps_over_optimal"]
            text = (
                f"{extra:.2f} steps over optimal, exact mean over the episodes "
                f"its greedy policy brings to the target ({solved:.1%} of them)"
            )
            rows.append(ScoreRow("Agent", text, f"{extra:.2f} extra steps, reaches {solved:.0%}"))
        if scope.exact:
            rows.append(ScoreRow("Optimum", "0 steps over optimal from every placement", "0 extra"))
        else:
            rows.append(ScoreRow("Optimum", f"a shortest path from every placement ({scope.note})",
                                 "shortest path (unwrapped)"))
        if watched is not None and watched.tally.episodes:
            watched_extra = watched.figure_mean("steps_over_optimal")
            more = "" if watched_extra is None else f"{watched_extra:.2f} extra steps"
            rows.append(watched_row(watched, self.game.episode_noun, AGREEMENT, more))
        return rows

    def episode_detail(
        self, first_info: Mapping[str, Any], length: int, total: float, terminated: bool
    ) -> dict[str, Any]:
        return {
            "length": length, "return": total, "terminated": terminated,
            "optimal": int(first_info.get("distance", 0)),
        }

    def eval_outcome(
        self, returns: Sequence[float], details: Sequence[dict[str, Any]]
    ) -> EvalOutcome:
        n = max(1, len(details))
        solved = [d for d in details if d["terminated"]]
        extra = [d["length"] - d["optimal"] for d in solved]
        return EvalOutcome(
            figures={
                "success_rate": len(solved) / n,
                "mean_steps_over_optimal": float(np.mean(extra)) if extra else float("nan"),
            }
        )


class GridWorldLayout(HeatmapLayout):
    """Max Q over the grid for one target, which a person moves."""

    has_focus = True
    focus_help = "move the heatmap's target"

    def heatmaps(
        self, q: np.ndarray, kwargs: Mapping[str, Any], focus: Any = None, marks: Any = None,
    ) -> list[Heatmap]:
        size = _size(kwargs)
        if np.shape(q) != (size**4, 4):
            return []
        tx, ty = focus if focus is not None else (size - 1, size - 1)
        walls = _walls(kwargs)
        wall_set = set(walls)
        q4 = q.reshape(size, size, size, size, q.shape[1])
        top = size - 1  # +y is up: row r is y = size-1-r

        def fixed(r: int, x: int) -> str | None:
            return "T" if (x, top - r) == (tx, ty) else WALL if (x, top - r) in wall_set else None

        return [greedy_panel(
            f"max Q with the target at ({tx}, {ty})",
            f"arrow: greedy move  {TIED} tie  T target  * off every shortest path"
            + (f"  {WALL} wall" if walls else ""), numbered(size)[::-1], numbered(size), fixed,
            lambda r, x: q4[x, top - r, tx, ty], ARROWS.__getitem__,
            lambda r, x, action: action not in _optimal_from(size, walls, (x, top - r), (tx, ty)),
        )]

    def default_focus(self, kwargs: Mapping[str, Any]) -> Any:
        size = _size(kwargs)
        return (size - 1, size - 1)

    def focus_at(self, row: int, col: int, kwargs: Mapping[str, Any]) -> Any:
        """The target (x, y) of a heatmap cell: the top row is y = size - 1."""
        size = _size(kwargs)
        row, col = min(size - 1, max(0, row)), min(size - 1, max(0, col))
        return (col, size - 1 - row)

    def focus_cell(self, focus: Any, kwargs: Mapping[str, Any]) -> tuple[int, int] | None:
        size = _size(kwargs)
        x, y = focus if focus is not None else self.default_focus(kwargs)
        return (size - 1 - int(y), int(x))


class GridWorldGame(Game):
    """Walk the agent to the target on a square grid."""

    name = "gridworld"
    title = "GridWorld"
    env_id = "tui_gym/GridWorld-v0"
    other_ids = ("gymnasium_env/GridWorld-v0",)
    key = "g"
    description = "Reach the target on a square grid; the tutorial's custom environment."
    teaches = "goal-conditioned states and discounting: why a shorter path is worth more"
    action_names = ("right", "up", "left", "down")
    params = (
        Param("size", int, 5, MIN_SIZE, MAX_SIZE, help="cells a side"),
        Param("reward_scale", float, 1.0, -100.0, 100.0, help="reward for reaching the target"),
        Param("step_penalty", float, 0.0, 0.0, 10.0, help="subtracted every other step"),
    )
    board = "grid"
    render_mode = "ansi"
    editable = True
    map_tools = ("floor", "wall")
    demo_wrappers = ("TimeLimit:max_episode_steps=50", "StepPenalty:penalty=0.01",
                     "DistanceShaping")

    # Reward only at the target: without discounting every path is worth 1
    # and the greedy policy would have no reason to take the shortest one.
    hyperparameters = {
        "*": {"discount": 0.95, "learning_rate": 0.1, "episodes": 20_000,
              "epsilon_decay_fraction": 0.5},
    }

    states_type = GridWorldStates
    oracle_type = GridWorldOracle
    narrator_type = GridWorldNarrator
    layout_type = GridWorldLayout

    def solution(self, kwargs: Mapping[str, Any]) -> Optimum | NotAvailable:
        """The optimum with action values that point its moves, where most returns tie: minus
        the steps to the target after each move (walled off: `size**2` steps)."""
        size, walls = _size(kwargs), _walls(kwargs)
        cells = size * size
        distance = cell_distances(size, walls).astype(np.float64)
        distance[distance < 0] = cells
        moves = cell_moves(size, walls)
        q = np.stack([-1.0 - distance[moves[a]] for a in range(4)], axis=-1).reshape(-1, 4)
        q[np.eye(cells, dtype=bool).reshape(-1)] = 0.0
        optimum = self.oracle.optimum(kwargs)
        return optimum if isinstance(optimum, NotAvailable) else replace(optimum, q=q)

    def plan_model(self, kwargs: Mapping[str, Any]) -> PlanModel:
        """The model with no limit, discounted as the learners discount it by default: with
        a reward only at the target, every path is worth as much undiscounted."""
        model = gridworld_model(*_model_args(kwargs, NO_CHANGES))
        gamma = self.hyperparameters["*"]["discount"]
        return PlanModel(model, gamma, self.episode_limit(kwargs))

    def normalize_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        """As `Game.normalize_kwargs`, with the walls: `layout` (a square map of F and W,
        whose side is the size) or `walls` (a list of (x, y) cells)."""
        rest = dict(kwargs)
        layout, walls = rest.pop(LAYOUT, None), rest.pop("walls", None)
        out = super().normalize_kwargs(rest)
        if layout:
            try:
                grid_map = read_layout(str(layout))
            except MapError as error:
                raise ValueError(f"GridWorld map: {error}") from None
            if "size" in rest and _size(out) != grid_map.rows:  # a new size crops or extends
                grid_map = grid_map.resized(_size(out), _size(out))
            return self.with_map(out, grid_map)
        if walls:
            size = _size(out)
            cells = [["F"] * size for _ in range(size)]
            for x, y in check_walls(size, walls):
                cells[size - 1 - y][x] = "W"
            return self.with_map(out, GridMap.of("".join(row) for row in cells))
        return out

    def with_map(self, kwargs: Mapping[str, Any], grid_map: Any) -> dict[str, Any]:
        """The arguments that play a square map of floor and walls (its side the size)."""
        if grid_map.rows != grid_map.cols or not MIN_SIZE <= grid_map.rows <= MAX_SIZE:
            raise ValueError(f"GridWorld plays a square map of {MIN_SIZE} to {MAX_SIZE} cells a "
                             f"side, not {grid_map.size_text}")
        others = sorted(grid_map.tiles() - {"F", "W"})
        if others:
            raise ValueError(f"GridWorld's map is floor (F) and walls (W) only, not "
                             f"{', '.join(others)}: agent and target are placed at random")
        check_walls(grid_map.rows, grid_map.walls_xy())
        out = {**kwargs, "size": grid_map.rows}
        out.pop(LAYOUT, None)
        if grid_map.walls_xy():
            out[LAYOUT] = format_map(grid_map)
        return out

    def grid_map(self, kwargs: Mapping[str, Any]) -> GridMap:
        return layout_map(kwargs) or GridMap.of(["F" * _size(kwargs)] * _size(kwargs))

    def make_kwargs(self, kwargs: Mapping[str, Any]) -> dict[str, Any]:
        out = {k: v for k, v in kwargs.items() if k != LAYOUT}
        walls = _walls(kwargs)
        if walls:
            out["walls"] = [list(w) for w in walls]
        return out

    def training_model(
        self, kwargs: Mapping[str, Any], changes: GameChanges = NO_CHANGES
    ) -> TrainingModel | NotAvailable:
        if changes.others:
            return NotAvailable(unwrapped_note(changes.others))
        return TrainingModel(gridworld_model(*_model_args(kwargs, changes)))
