"""The session: one env, a choice of wrappers, one learner (the agent) and its trainer."""

from __future__ import annotations

import copy
import weakref
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.algorithms import DEFAULT_ALGORITHM, Learner, Predictor, Settings
from tui_gym.algorithms import algorithm as learner_class_named
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.core.engine.stats import TrainingSnapshot
from tui_gym.core.engine.trainer import Trainer
from tui_gym.core.heatmap import Heatmap
from tui_gym.core.mdp import FiniteMDP, NotAvailable
from tui_gym.core.mdp.prediction import Truth
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.wrappers import CATALOG, WrapperChoice, build_env, build_env_lenient, chain
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.games import GAMES, Game, game_for, resolve_env_id
from tui_gym.games.base import FixedBound, ReferenceMetrics, TrainingModel
from tui_gym.games.model import ModelGame
from tui_gym.session.evaluation import EvalReport, evaluate

ENGINES = ("auto", "model", "env")
# With a target gap and no budget given, the budget is the game's default times this,
# so epsilon decays more slowly (the run stops at the target anyway).
TARGET_GAP_BUDGET_FACTOR = 5

# Observation wrappers whose `observation()` is a pure function of the bare
# observation: the heatmaps and the exact reference can see through them.
STATELESS_OBSERVATION_WRAPPERS = frozenset({"FlattenObservation"})
# The loop's arrays of each model a game keeps (its exact model), by table rows: a second
# session or learner on the same model reuses them (the loop only reads them).
_ARRAYS: weakref.WeakKeyDictionary[FiniteMDP, dict[bytes, ModelArrays]] = (
    weakref.WeakKeyDictionary())


@dataclass(frozen=True)
class RebuildReport:
    """What a rebuild did: whether the agent survived, and why not."""

    kept_agent: bool
    notice: str
    skipped: tuple[tuple[WrapperChoice, str], ...] = ()


@dataclass(frozen=True)
class PredictionFigures:
    """A prediction learner's RMS error of V, and per reached model state its estimate and
    true value."""

    rms: float
    states: tuple[int, ...]
    estimate: tuple[float, ...]
    truth: tuple[float, ...]


@dataclass(frozen=True)
class TrainOutcome:
    """How a headless run ended: whether it met its target gap, and the last gap checked."""

    reached_target: bool | None  # None: no target was set
    gap: float | None


@dataclass
class _Built:
    env: gym.Env
    applied: tuple[WrapperChoice, ...]
    skipped: tuple[tuple[WrapperChoice, str], ...]
    keyer: ObservationKeyer
    n_actions: int
    meaning: tuple[str, ...]  # what keys mean: the space and the observation-changing wrappers


def _build(
    game: Game, env_id: str, env_kwargs: Mapping[str, Any], choices: Sequence[WrapperChoice]
) -> _Built:
    env, skipped = build_env_lenient(game.make_id(env_id, env_kwargs),
                                     game.make_kwargs(env_kwargs), choices)
    skipped_set = {id(c) for c, _ in skipped}
    applied = tuple(c for c in choices if id(c) not in skipped_set)
    if not isinstance(env.action_space, gym.spaces.Discrete):
        env.close()
        raise ValueError(f"{env_id} has a {type(env.action_space).__name__} action space; "
                         "a Q-table needs Discrete actions")
    keyer = ObservationKeyer(env.observation_space)
    meaning = (keyer.signature, *(c.name for c in applied if CATALOG[c.name].changes_observation))
    return _Built(env, applied, tuple(skipped), keyer, int(env.action_space.n), meaning)


def default_settings(game: Game, name: str, kwargs: Mapping[str, Any] | None = None) -> Settings:
    """Algorithm `name`'s defaults with the game's overrides for it (at arguments `kwargs`)."""
    cls = learner_class_named(name)
    fields = {f.name for f in cls.params}
    overrides = game.default_hyperparameters(cls.name, kwargs,
                                             prediction=issubclass(cls, Predictor))
    return cls.settings({k: v for k, v in overrides.items() if k in fields})


@dataclass(init=False)
class Session:
    """One game with its wrappers, learner and trainer; what every front end drives.

    `hp` overrides the game's defaults for the algorithm (another schema's `Settings`
    give the values the two share); once built it holds the algorithm's `Settings`.
    """

    env_id: str  # "": the first game of the registry
    env_kwargs: dict[str, Any]
    choices: tuple[WrapperChoice, ...]
    hp: Settings
    seed: int
    engine: str  # "auto" (the model when the wrappers allow), "model" or "env"
    algorithm: str  # a name in the ALGORITHMS registry

    def __init__(
        self, env_id: str = "", env_kwargs: Mapping[str, Any] | None = None,
        choices: Sequence[WrapperChoice] = (), hp: Settings | Mapping[str, Any] | None = None,
        seed: int = 0, engine: str = "auto", algorithm: str = DEFAULT_ALGORITHM,
    ) -> None:
        self.env_id = resolve_env_id(env_id or GAMES[0].env_id)
        self.game: Game = game_for(self.env_id)
        self.env_kwargs = self.game.normalize_kwargs(env_kwargs or {})
        self.learner_class: type[Learner] = learner_class_named(algorithm)
        self.algorithm = self.learner_class.name
        self.hp = self._settings(hp)
        self.seed = seed
        self.choices = tuple(choices)
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}")
        self.engine = engine
        self._install(_build(self.game, self.env_id, self.env_kwargs, self.choices))
        self._new_agent()

    # --- building ---------------------------------------------------------
    def _install(self, built: _Built) -> None:
        self._built = built
        self.env = built.env
        self.keyer = built.keyer
        self.applied = built.applied  # the chosen wrappers that fit and are in the env
        self.skipped = built.skipped  # those that do not fit, each with the reason
        # What the exact figures must take into account.
        self.changes = GameChanges.of(built.env, self.game.episode_limit(self.env_kwargs))
        self._base_keys: list[Hashable] | None | bool = False  # False: not computed yet

    def _settings(self, hp: Settings | Mapping[str, Any] | None) -> Settings:
        """`hp` as this algorithm's settings over the game's defaults (see the class)."""
        base = default_settings(self.game, self.algorithm, self.env_kwargs)
        if hp is None:
            return base
        values = dict(hp)
        if isinstance(hp, Settings) and hp.schema != self.learner_class.params:
            values = {k: v for k, v in values.items() if k in base}
        return base.replace(**values)

    def _new_agent(self) -> None:
        """A fresh agent and its trainer."""
        self.agent = self.learner_class(self._built.n_actions, self.hp,
                                        n_states=self.keyer.n_states, seed=self.seed)
        self.trainer = self._new_trainer()

    def _new_trainer(self) -> Trainer:
        """The trainer, on the game's model where there is one (`engine_reason` says why)."""
        phases, self.engine_reason = self._training_model()
        self.agent.offer(self._offered())
        return Trainer(self.env, self.agent, self.keyer, model=phases[0][1] if phases else None,
                       later=phases[1:], seed=self.seed, reason=self.engine_reason)

    def _offered(self) -> np.ndarray | None:
        """The actions each table row offers, where the game's model says (else None)."""
        training, rows = self.training, self.keyer.n_states
        if training is None or rows is None or not isinstance(self.game, ModelGame):
            return None
        offered = self.game.offered_actions(self.env_kwargs)
        model = training.model
        if offered is None or offered.shape != (model.n_states, model.n_actions):
            return None
        mask = np.ones((rows, model.n_actions), dtype=bool)
        mask[training.rows] = offered
        return mask

    def _training_model(self) -> tuple[tuple[tuple[int, ModelArrays], ...], str]:
        """The (start step, arrays) of each phase the compiled loop trains on, or none, and
        why (`training` keeps the game's model, also when the env loop is chosen)."""
        self.training: TrainingModel | None = None
        self._truth_kept: tuple[Any, Truth] | None = None
        changed = [c.name for c in self.applied if CATALOG[c.name].changes_observation]
        others = self.changes.others
        found: Any = None
        if changed or others:
            names = changed or others
            what = "the observations" if changed else "the game beyond what its model follows"
            reason = f"{', '.join(names)} change{'s' if len(names) == 1 else ''} {what}"
        elif not self.keyer.dense:
            reason = "its observations are not table rows"
        else:
            found = self.game.training_model(self.env_kwargs, self.changes)
            reason = found.reason if isinstance(found, NotAvailable) else ""
        if not reason:
            model = found.model
            rows = np.arange(model.n_states) if found.rows is None else found.rows
            if model.n_actions != self._built.n_actions or rows.max() >= (self.keyer.n_states or 0):
                reason = "its model does not fit the env's observations and actions"
            else:
                self.training = TrainingModel(model, rows, found.later)
        if self.engine == "env":
            return (), "env: chosen"
        if self.training is not None:
            names = [label.partition("(")[0] for label in self.changes.reward_wrappers]
            if self.changes.chosen_time_limit:
                names.append("TimeLimit")
            text = f"model: {self.game.title}" + (f" with {', '.join(names)}" if names else "")
            phases = ((0, self.training.model), *self.training.later)
            return tuple((start, _arrays_of(m, rows)) for start, m in phases), text
        if self.engine == "model":
            raise ValueError(f"the model loop cannot train this: {reason}")
        return (), f"env: {reason}"

    def chain_repr(self) -> str:
        """The env's wrapper chain as Gymnasium prints it."""
        return str(self.env)

    def make_env(self, render_mode: str | None = None) -> gym.Env:
        """A new env like the training one (same game, same wrappers), e.g. to play on."""
        return build_env(self.game.make_id(self.env_id, self.env_kwargs),
                         self.game.make_kwargs(self.env_kwargs), self.applied,
                         render_mode=render_mode)

    def rebuild(
        self, env_id: str | None = None, env_kwargs: Mapping[str, Any] | None = None,
        choices: Sequence[WrapperChoice] | None = None,
    ) -> RebuildReport:
        """Change game, env arguments or wrappers; keep the agent when keys keep their meaning
        (ValueError, changing nothing, for an unknown env or bad arguments)."""
        new_id, kwargs, new_choices, game, built = self._rebuilt(env_id, env_kwargs, choices)
        keep = self._keeps(built)
        defaults = default_settings(self.game, self.algorithm, self.env_kwargs)
        if game is not self.game or (not keep and self.hp == defaults):
            # Each game (and a larger map) learns with its own defaults; a fresh agent on
            # the same game keeps hyperparameters a person chose.
            self.hp = default_settings(game, self.algorithm, kwargs)
        old_trainer = self.trainer
        self.env.close()
        self.env_id, self.env_kwargs, self.choices, self.game = (new_id, kwargs, new_choices, game)
        self._install(built)
        if keep:
            self.trainer = self._new_trainer()
            self.trainer.restore(old_trainer.progress())
            notice = "Env rebuilt; the agent is kept (observations mean the same)."
        else:
            self._new_agent()
            notice = "Observations changed meaning, so the agent was reset."
        if built.skipped:
            notice += " Not applied: " + "; ".join(reason for _, reason in built.skipped)
        return RebuildReport(keep, notice, built.skipped)

    def rebuild_keeps_agent(
        self, env_id: str | None = None, env_kwargs: Mapping[str, Any] | None = None,
        choices: Sequence[WrapperChoice] | None = None,
    ) -> bool:
        """Whether `rebuild` with these arguments would keep the agent (changes nothing)."""
        built = self._rebuilt(env_id, env_kwargs, choices)[-1]
        built.env.close()  # only its meaning is compared
        return self._keeps(built)

    def _rebuilt(
        self, env_id: str | None, env_kwargs: Mapping[str, Any] | None,
        choices: Sequence[WrapperChoice] | None,
    ) -> tuple[str, dict[str, Any], tuple[WrapperChoice, ...], Game, _Built]:
        """The env id, checked arguments, wrappers and game a rebuild would use, and the env
        built from them."""
        new_id = self.env_id if env_id is None else resolve_env_id(env_id)
        game = game_for(new_id)
        if env_kwargs is None:
            env_kwargs = self.env_kwargs if new_id == self.env_id else game.default_kwargs()
        kwargs = game.normalize_kwargs(env_kwargs)
        new_choices = tuple(self.choices if choices is None else choices)
        return new_id, kwargs, new_choices, game, _build(game, new_id, kwargs, new_choices)

    def _keeps(self, built: _Built) -> bool:
        """Whether the agent can learn on `built`: its keys mean what they meant."""
        return built.meaning == self._built.meaning and built.n_actions == self._built.n_actions

    def reset_agent(self) -> None:
        """A fresh agent (same seed) and fresh statistics."""
        self.env.close()
        self._install(_build(self.game, self.env_id, self.env_kwargs, self.choices))
        self._new_agent()

    def set_hyperparameters(self, hp: Settings | Mapping[str, Any]) -> None:
        """New hyperparameters from now on, the tables kept; a mapping may name some only.
        ValueError, changing nothing, for a bad value."""
        if not (isinstance(hp, Settings) and hp.schema == self.hp.schema):
            hp = self.hp.replace(**dict(hp))
        self.agent.set_hyperparameters(hp)
        self.hp = hp

    def follow(self, other: Session, epsilon: float = 0.0) -> None:
        """The prediction learner follows `other`'s agent's epsilon-greedy policy (its table
        now); ValueError, changing nothing, unless both play the same game and states."""
        agent = self.agent
        if not isinstance(agent, Predictor):
            raise ValueError(f"{self.learner_class.title} is not a prediction learner: it "
                             "follows its own policy")
        same = (other.env_id, other.env_kwargs, other._built.meaning) == (
            self.env_id, self.env_kwargs, self._built.meaning)
        if not (same and self.keyer.dense and other.keyer.dense):
            raise ValueError(f"the agent to follow plays {other.game.title} "
                             f"{other.env_kwargs or ''}, not {self.game.title} "
                             f"{self.env_kwargs or ''} with the same wrappers")
        agent.follow(other.agent.values(range(agent.rows_used)), epsilon)
        self.hp = agent.hp

    def set_algorithm(self, name: str) -> None:
        """A fresh learner of another algorithm with the game's defaults for it, and fresh
        statistics; ValueError, changing nothing, for an unknown name."""
        cls = learner_class_named(name)
        self.learner_class, self.algorithm = cls, cls.name
        self.hp = default_settings(self.game, cls.name, self.env_kwargs)
        self.reset_agent()

    def detached(self) -> Session:
        """A shallow copy for a thread to read exact figures from while this one is rebuilt
        (it shares the game, agent and env); its base keys are computed first."""
        self.base_keys()
        return copy.copy(self)

    # --- seeing the table -------------------------------------------------
    def base_keys(self) -> list[Hashable] | None:
        """Table keys of the game's base states, or None when wrappers hide them (or none)."""
        if self._base_keys is False:
            keys: list[Hashable] | None = None
            observations = None
            if not self._history_wrappers():
                observations = self.game.states.base_observations(self.env_kwargs)
            if observations is not None and not isinstance(observations, NotAvailable):
                layers = [layer for layer in chain.layers(self.env)
                          if isinstance(layer, gym.ObservationWrapper)]
                keys = []
                for obs in observations:
                    for layer in layers:
                        obs = layer.observation(obs)
                    keys.append(self.keyer.key(obs))
            self._base_keys = keys
        return self._base_keys  # type: ignore[return-value]

    def _history_wrappers(self) -> list[str]:
        """The applied wrappers whose observations depend on more than the bare one."""
        return [c.name for c in self.applied if CATALOG[c.name].changes_observation
                and c.name not in STATELESS_OBSERVATION_WRAPPERS]

    def hidden_reason(self) -> str:
        """Why heatmaps and the exact reference are unavailable (empty when they are)."""
        if self.base_keys() is not None:
            return ""
        observations = self.game.states.base_observations(self.env_kwargs)
        if isinstance(observations, NotAvailable):
            return observations.reason
        return (f"{', '.join(self._history_wrappers())} makes observations depend on history; "
                "no per-state view")

    def base_q(self, snapshot: TrainingSnapshot | None = None) -> np.ndarray | None:
        """Q-values of the base states (from a snapshot, or the live agent)."""
        keys = self.base_keys()
        if keys is None:
            return None
        return (self.agent if snapshot is None else snapshot).values(keys)

    @property
    def predicts(self) -> bool:
        """Whether the learner is a prediction learner (it scores a fixed policy)."""
        return isinstance(self.agent, Predictor)

    def prediction(self, snapshot: TrainingSnapshot | None = None) -> PredictionFigures | None:
        """A prediction learner's V (live, or a snapshot's) against its policy's exact values;
        None for a control learner or without them (`prediction_reason` says why)."""
        agent, training = self.agent, self.training
        if not isinstance(agent, Predictor) or training is None:
            return None
        try:
            truth = self._truth()
            v = agent.v[training.rows] if snapshot is None else snapshot.q[training.rows, 0]
            where = np.flatnonzero(truth.reached)
            return PredictionFigures(truth.rms(v), tuple(int(s) for s in where),
                                     tuple(float(x) for x in v[where]),
                                     tuple(float(x) for x in truth.v[where]))
        except ValueError:
            return None

    def _truth(self) -> Truth:
        """The exact values of the policy the prediction learner follows (ValueError when there
        are none), computed again only when it changes."""
        agent, training = self.agent, self.training
        assert isinstance(agent, Predictor) and training is not None
        key = (id(training.model), agent.hp.discount, agent.epsilon,
               agent.q[training.rows].tobytes())
        kept = self._truth_kept  # one assignment: safe across threads
        if kept is None or kept[0] != key:
            kept = self._truth_kept = (key, agent.truth(training.model, training.rows))
        return kept[1]

    def prediction_reason(self) -> str:
        """Why a prediction learner has no RMS error here ('' when it has one)."""
        if not self.predicts:
            return "not a prediction learner"
        if self.training is None:
            return f"no exact values here ({self.engine_reason})"
        try:
            self._truth()
        except ValueError as error:
            return str(error)
        return ""

    def exact_kwargs(self, snapshot: TrainingSnapshot | None = None) -> dict[str, Any]:
        """The game's arguments for the exact figures: in a world that changes, the phase in
        force after the steps trained (live, or a snapshot's)."""
        steps = self.trainer.steps if snapshot is None else snapshot.steps
        return self.game.at_step(self.env_kwargs, steps)

    def reference(self, snapshot: TrainingSnapshot | None = None) -> ReferenceMetrics | None:
        """The exact comparison of the greedy policy with the optimum (None: see `exact_reason`)."""
        return self._exact(self.game.oracle.reference, snapshot)

    def evaluation_reference(self) -> ReferenceMetrics | None:
        """`reference()` with what only an evaluation asks for (see the game's oracle)."""
        return self._exact(self.game.oracle.evaluation_reference)

    def _exact(self, figures: Callable[..., Any], snapshot: TrainingSnapshot | None = None,
               reason: bool = False) -> Any:
        """`figures(q, kwargs, changes)` of the base states' Q (None when hidden or not
        available; with `reason`, why not: '' when it is)."""
        q = self.base_q(snapshot)
        found = None if q is None else figures(q, self.exact_kwargs(snapshot), self.changes)
        if reason:
            return found.reason if isinstance(found, NotAvailable) else ""
        return None if isinstance(found, NotAvailable) else found

    def exact_reason(self) -> str:
        """Why there are no exact figures of the agent here ('' when there are)."""
        return self.hidden_reason() or self._exact(self.game.oracle.reference, reason=True)

    def heatmaps(
        self, snapshot: TrainingSnapshot | None = None, focus: Any = None, traces: bool = False,
    ) -> list[Heatmap] | None:
        """The game's heatmap panels of the table (None when wrappers hide the states); with
        `traces`, of a snapshot's eligibility traces, unmarked (ValueError without one)."""
        kwargs = self.exact_kwargs(snapshot)
        if not traces:
            q = self.base_q(snapshot)
            if q is None:
                return None
            marks = self.game.oracle.optimal_marks(kwargs, self.changes)
            return self.game.layout.heatmaps(self._among_offered(q, kwargs), kwargs, focus, marks)
        if snapshot is None:
            raise ValueError("the traces shown are a snapshot's")
        keys = self.base_keys()
        if keys is None:
            return None
        return self.game.layout.heatmaps(snapshot.values(keys, traces=True), kwargs, focus)

    def _among_offered(self, q: np.ndarray, kwargs: Mapping[str, Any]) -> np.ndarray:
        """`q` with the actions a state does not offer at -inf (as the agent sees them)."""
        if self.agent.offered is None or not isinstance(self.game, ModelGame):
            return q
        offered = self.game.offered_actions(kwargs)
        if offered is None or offered.shape != q.shape:
            return q
        offered = offered | ~offered.any(axis=1, keepdims=True)  # none offered: all are
        return np.where(offered, q, -np.inf)

    def heatmap_cell(
        self, observation: Any, focus: Any = None
    ) -> tuple[Any, tuple[int, int, int]] | None:
        """The focus to show an observation's state under (`focus` when it is there, else
        the first that has it) and its (panel, row, col); None when no heatmap shows it."""
        keys = self.base_keys()
        if keys is None:
            return None
        try:
            key = self.keyer.key(observation)
        except (IndexError, KeyError, TypeError, ValueError):
            return None
        rows = [i for i, k in enumerate(keys) if k == key]
        if not rows:
            return None
        # An indicator table: the state's cell is the only one whose value is 1.
        q = np.zeros((len(keys), self._built.n_actions))
        q[rows] = 1.0
        layout, kwargs = self.game.layout, self.env_kwargs
        focuses = [focus]
        if layout.has_focus:
            panels = layout.heatmaps(q, kwargs, focus)
            height, width = panels[0].shape if panels else (0, 0)
            focuses += [layout.focus_at(r, c, kwargs) for r in range(height) for c in range(width)]
        for candidate in focuses:
            for index, panel in enumerate(layout.heatmaps(q, kwargs, candidate)):
                found = np.argwhere(np.nan_to_num(panel.values) == 1.0)
                if found.size:
                    return candidate, (index, int(found[0][0]), int(found[0][1]))
        return None

    def agent_figures(self, snapshot: TrainingSnapshot | None = None) -> dict[str, float]:
        """Exact scoreboard figures of the greedy policy (live, or a snapshot's) and of the
        optimum (`Oracle.agent_figures`); the optimum's only when wrappers hide the states."""
        return self.game.oracle.agent_figures(self.base_q(snapshot),
                                              self.exact_kwargs(snapshot), self.changes)

    def shortfall(self, reference: ReferenceMetrics) -> str:
        """A sentence saying why the policy `reference` measured ends short of the game's
        stated bound ('' when it meets it, or there is none)."""
        bound = self.game.oracle.bound(self.env_kwargs, self.changes)
        if isinstance(bound, NotAvailable) or bound.met(reference.figures):
            return ""
        value = reference.figures.get(bound.figure, float("nan"))
        why = self.game.lessons.get(self.algorithm) or (
            "the greedy policy has not got there yet with these settings; more episodes "
            "or a smaller learning rate would close the rest")
        figure = bound.figure.replace("_", " ")
        return f"It ends short of the bound ({bound.text}; {figure} {value:.4g}): {why}."

    def fixed_policy_bound(self) -> FixedBound | None:
        """How close a fixed (greedy) policy gets to the optimum here, when known."""
        bound = self.game.oracle.fixed_policy_bound(self.exact_kwargs(), self.changes)
        return None if isinstance(bound, NotAvailable) else bound

    def greedy_actions_for(
        self, observation: Any, snapshot: TrainingSnapshot | None = None
    ) -> tuple[tuple[int, ...], np.ndarray] | None:
        """The offered actions tied for the best value on an observation of this env, and the
        state's Q-values, of the live agent or `snapshot`; None for a state never updated
        (a snapshot's: all 0) or an observation that does not fit. Only reads the table."""
        agent = self.agent
        try:
            key = self.keyer.key(observation)
            if snapshot is not None:
                q = snapshot.values([key])[0]
                if not q.any():
                    return None
            else:
                if not agent.seen(key):
                    return None
                q = agent.values([key])[0]
            row, among = agent.find(key), q
            if agent.offered is not None and row is not None:  # the actions the state offers
                among = np.where(agent.offered[row], q, -np.inf)
        except (IndexError, KeyError, TypeError, ValueError):  # a mismatched or moving table
            return None
        return tuple(int(a) for a in np.flatnonzero(among == among.max())), q

    # --- headless training ------------------------------------------------
    def train(
        self, target_gap: float | None = None, check_every: int | None = None,
        chunk_seconds: float = 0.2, on_chunk: Callable[[TrainingSnapshot], None] | None = None,
    ) -> TrainOutcome:
        """Train to the end of the budget, or until the exact gap, checked every `check_every`
        episodes (`check_every_for`), is at most `target_gap`; `on_chunk` sees a snapshot
        after each chunk of about `chunk_seconds`."""
        if target_gap is not None:
            self.check_target_gap(target_gap)
        trainer = self.trainer
        if check_every is None:
            check_every = check_every_for(trainer.remaining)
        next_check = trainer.episodes + check_every
        while trainer.remaining > 0:
            limit = trainer.remaining
            if target_gap is not None:
                limit = min(limit, max(1, next_check - trainer.episodes))
            trainer.run(episodes=limit, seconds=chunk_seconds)
            if on_chunk is not None:
                on_chunk(trainer.latest)
            if target_gap is not None and trainer.episodes >= next_check:
                next_check = trainer.episodes + check_every
                gap = self.reference().figures["gap"]  # type: ignore[union-attr]
                if gap <= target_gap:
                    return TrainOutcome(True, gap)
        if target_gap is None:
            return TrainOutcome(None, None)
        gap = self.reference().figures["gap"]  # type: ignore[union-attr]
        return TrainOutcome(gap <= target_gap, gap)

    def check_target_gap(self, target_gap: float) -> None:
        """`ValueError` when no greedy policy can meet `target_gap` here."""
        ref = self.reference()
        if ref is None or "gap" not in ref.figures:
            why = self.exact_reason() or f"{self.game.title} has no exact gap"
            raise ValueError(f"--target-gap needs an exact optimum: {why}")
        bound = self.fixed_policy_bound()
        if bound is not None and target_gap < bound.shortfall:
            raise ValueError(
                f"no fixed policy found comes within {target_gap:g} of the optimum here: the "
                f"best one a search finds stays {bound.shortfall:.4f} below it (the optimum "
                "plays differently as the episode limit nears); choose --target-gap "
                f">= {_round_up(bound.shortfall)}"
            )

    # --- evaluating, saving -----------------------------------------------
    def evaluate(
        self, episodes: int = 10_000, seed: int | None = None,
        progress: Callable[[int], None] | None = None,
    ) -> EvalReport:
        """Greedy play on a fresh env; `seed` defaults to one derived from the session's."""
        eval_seed = self.seed + 1_000_003 if seed is None else seed
        with self.make_env() as env:
            report = evaluate(env, self.agent, self.keyer, self.game.narrator, episodes, eval_seed,
                              progress)
        return report

    def meta(self) -> dict[str, Any]:
        """Everything a save file keeps besides the table, as JSON data."""
        from tui_gym.core.wrappers import format_wrapper_spec

        return {
            "env_id": self.env_id, "env_kwargs": self.env_kwargs,
            "wrappers": [format_wrapper_spec(c) for c in self.choices], "algorithm": self.algorithm,
            "hyperparameters": self.hp.to_dict(), "seed": self.seed,
            "episodes_trained": self.trainer.episodes, "steps_trained": self.trainer.steps,
            "agent_episode": self.agent.episode, "n_actions": self.agent.n_actions,
            "observation_space": self.keyer.signature,
        }

    def save(self, path: str | Path) -> Path:
        """Write the agent and everything needed to rebuild this session (atomically)."""
        from tui_gym.session.storage import save_agent

        return save_agent(path, self.meta(), self.agent.state())

    @classmethod
    def load(cls, path: str | Path) -> Session:
        """A session rebuilt from a saved file; StorageError names the file and field when not."""
        from tui_gym.session.storage import read_agent, short_reason

        saved = read_agent(path)
        game = saved.checked("env_id", lambda: game_for(saved.env_id))
        env_kwargs = saved.checked("env_kwargs", lambda: game.normalize_kwargs(saved.env_kwargs))
        try:
            session = cls(env_id=saved.env_id, env_kwargs=env_kwargs, choices=saved.choices,
                          hp=saved.hp, seed=saved.seed, algorithm=saved.algorithm.name)
        except (ValueError, TypeError, KeyError) as exc:
            raise saved.error(f"cannot rebuild the saved game ({short_reason(exc)})") from None
        session._restore(saved)
        return session

    def _restore(self, saved: Any) -> None:
        """A saved learner state into the agent and its counts into the trainer."""
        from tui_gym.session.storage import short_reason

        agent = self.agent
        if self.skipped:
            choice, reason = self.skipped[0]
            index = list(saved.choices).index(choice)
            raise saved.field(f"wrappers[{index}]", f"does not fit {self.env_id}: {reason}")
        n_actions = agent.n_actions if saved.n_actions is None else saved.n_actions
        if n_actions != agent.n_actions:
            raise saved.field("n_actions", f"is {n_actions}; {self.env_id} with these wrappers "
                              f"has {agent.n_actions}")
        member = f"{saved.table_name}.npy"
        first = saved.arrays[saved.table_name]
        if first.shape[1] != agent.n_actions:
            raise saved.field(member, f"has {first.shape[1]} columns; {self.env_id} has "
                              f"{agent.n_actions} actions")
        rows, keys = agent.n_states, saved.keys
        if rows is not None and keys is not None:
            raise saved.field("keys.json", f"is for a sparse table; {self.env_id}'s is dense")
        if rows is not None and len(first) != rows:
            raise saved.field(member, f"has {len(first):,} rows; {self.env_id} has {rows:,}")
        if rows is None and keys is None:
            raise saved.field("keys.json", "is missing (the states of the sparse table's rows)")
        saved.check_learner_meta()
        try:
            agent.load_state(saved.state(n_actions, rows))
        except (KeyError, TypeError, ValueError) as exc:
            raise saved.error(f"cannot restore the saved agent ({short_reason(exc)})") from None
        self.trainer.episodes = saved.episodes
        self.trainer.steps = saved.steps
        self.trainer.publish()


def check_every_for(budget: int) -> int:
    """Episodes between exact gap checks on a run of `budget` episodes."""
    return max(1_000, min(10_000, budget // 20))


def _round_up(value: float) -> str:
    """A value rounded up to 2 significant digits, as text: 0.0274 -> '0.028'."""
    import math

    if value <= 0:
        return "0"
    digits = 1 - int(math.floor(math.log10(value)))
    scale = 10.0**digits
    return f"{math.ceil(value * scale - 1e-9) / scale:.{max(digits, 0)}f}"


def _arrays_of(model: FiniteMDP, rows: np.ndarray) -> ModelArrays:
    """`ModelArrays.of(model, rows)`, built once per model and rows."""
    built = _ARRAYS.setdefault(model, {})
    key = np.asarray(rows, dtype=np.int64).tobytes()
    return built[key] if key in built else built.setdefault(key, ModelArrays.of(model, rows))
