"""The session: one env, a choice of wrappers, one agent and its trainer.

`Session` is the object every front end drives (the Textual app, the CLI,
tests, the JSON-lines protocol). It builds the env through the wrapper
catalog, keeps the agent when a rebuild leaves the observation keys meaning
the same thing (and says so when it cannot), projects the Q-table onto the
game's base states for heatmaps and the exact reference, evaluates, saves and
loads.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tui_gym.core.agent import Hyperparameters, QAgent
from tui_gym.core.evaluation import EvalReport, evaluate
from tui_gym.core.heatmap import Heatmap
from tui_gym.core.obskey import ObservationKeyer
from tui_gym.core.profiles import GameProfile, ReferenceMetrics, profile_for, resolve_env_id
from tui_gym.core.wrappers.changes import GameChanges
from tui_gym.core.training import Trainer, TrainingSnapshot
from tui_gym.core.vector import NoBatchedForm, VectorTrainer
from tui_gym.core.wrappers import (
    CATALOG,
    WrapperChoice,
    build_env,
    build_env_lenient,
)

ENGINES = ("auto", "scalar", "vector")

# Observation wrappers whose `observation()` is a pure function of the bare
# observation: the heatmaps and the exact reference can see through them.
STATELESS_OBSERVATION_WRAPPERS = frozenset({"FlattenObservation"})


@dataclass(frozen=True)
class RebuildReport:
    """What a rebuild did: whether the agent survived, and why not."""

    kept_agent: bool
    notice: str
    skipped: tuple[tuple[WrapperChoice, str], ...] = ()


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


def _build(env_id: str, env_kwargs: Mapping[str, Any], choices: Sequence[WrapperChoice]) -> _Built:
    env, skipped = build_env_lenient(env_id, env_kwargs, choices)
    skipped_set = {id(c) for c, _ in skipped}
    applied = tuple(c for c in choices if id(c) not in skipped_set)
    if not isinstance(env.action_space, gym.spaces.Discrete):
        env.close()
        raise ValueError(
            f"{env_id} has a {type(env.action_space).__name__} action space; "
            "a Q-table needs Discrete actions"
        )
    keyer = ObservationKeyer(env.observation_space)
    meaning = (keyer.signature, *(c.name for c in applied if CATALOG[c.name].changes_observation))
    return _Built(env, applied, tuple(skipped), keyer, int(env.action_space.n), meaning)


@dataclass
class Session:
    """One game with its wrappers, agent and trainer; what every front end drives."""

    env_id: str = "Blackjack-v1"
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    choices: tuple[WrapperChoice, ...] = ()
    hp: Hyperparameters | None = None  # None: the game's own defaults
    seed: int = 0
    engine: str = "auto"  # "auto" (vector when the wrappers allow), "scalar" or "vector"

    def __post_init__(self) -> None:
        self.env_id = resolve_env_id(self.env_id)
        self.profile: GameProfile = profile_for(self.env_id)
        self.env_kwargs = self.profile.normalize_kwargs(self.env_kwargs)
        if self.hp is None:
            self.hp = self.profile.default_hyperparameters()
        self.choices = tuple(self.choices)
        if self.engine not in ENGINES:
            raise ValueError(f"engine must be one of {', '.join(ENGINES)}, got {self.engine!r}")
        self._install(_build(self.env_id, self.env_kwargs, self.choices))
        self.agent = self._new_agent()
        self.trainer = self._new_trainer()

    # --- building ---------------------------------------------------------
    def _install(self, built: _Built) -> None:
        self._built = built
        self.env = built.env
        self.keyer = built.keyer
        self.changes = GameChanges.of(built.env)  # what the exact figures must take into account
        self._base_keys: list[Hashable] | None | bool = False  # False: not computed yet

    def _new_agent(self) -> QAgent:
        return QAgent(self._built.n_actions, self.hp, n_states=self.keyer.n_states, seed=self.seed)

    def _new_trainer(self) -> Trainer:
        """The trainer for the chosen engine; `engine_reason` says which and why."""
        self._scalar: Trainer | None = None
        self._vector: Trainer | None = None
        if self.engine != "scalar":
            try:
                self._vector = VectorTrainer(self.env, self.agent, self.keyer, seed=self.seed)
            except (NoBatchedForm, ValueError) as exc:
                reason = str(exc).removeprefix("scalar engine: ")
                if self.engine == "vector":
                    raise ValueError(f"the vector engine cannot run this: {reason}") from None
                self.engine_reason = f"scalar engine: {reason}"
            else:
                self.engine_reason = self._vector.plan.describe()
                return self._vector
        else:
            self.engine_reason = "scalar engine: chosen"
        self._scalar = Trainer(self.env, self.agent, self.keyer, seed=self.seed)
        return self._scalar

    def trainer_for(self, animated: bool) -> Trainer:
        """The trainer to use now: animation needs single steps, so the scalar engine.

        Switching hands the counts and statistics over, so the run reads as one.
        """
        if animated and self.trainer.engine != "scalar":
            if self._scalar is None:
                self._scalar = Trainer(self.env, self.agent, self.keyer, seed=self.seed + 1)
            self._scalar.adopt_progress(self.trainer)
            self.trainer = self._scalar
        elif not animated and self._vector is not None and self.trainer is not self._vector:
            self._vector.adopt_progress(self.trainer)
            self.trainer = self._vector
        return self.trainer

    @property
    def applied(self) -> tuple[WrapperChoice, ...]:
        """The chosen wrappers that fit and are in the env."""
        return self._built.applied

    @property
    def skipped(self) -> tuple[tuple[WrapperChoice, str], ...]:
        """The chosen wrappers that do not fit, each with the reason."""
        return self._built.skipped

    def chain_repr(self) -> str:
        """The env's wrapper chain as Gymnasium prints it."""
        return str(self.env)

    def make_env(self, render_mode: str | None = None) -> gym.Env:
        """A new env like the training one (same game, same wrappers), e.g. to play on."""
        return build_env(self.env_id, self.env_kwargs, self.applied, render_mode=render_mode)

    def rebuild(
        self,
        env_id: str | None = None,
        env_kwargs: Mapping[str, Any] | None = None,
        choices: Sequence[WrapperChoice] | None = None,
    ) -> RebuildReport:
        """Change game, env arguments or wrappers; keep the agent when keys keep their meaning.

        Raises ValueError (and changes nothing) for an unknown env or bad arguments.
        """
        new_id = resolve_env_id(env_id) if env_id is not None else self.env_id
        profile = profile_for(new_id)
        if env_kwargs is None:
            kwargs = self.env_kwargs if new_id == self.env_id else profile.default_kwargs()
        else:
            kwargs = env_kwargs
        kwargs = profile.normalize_kwargs(kwargs)
        new_choices = tuple(self.choices if choices is None else choices)
        built = _build(new_id, kwargs, new_choices)
        if profile is not self.profile:
            # Each game learns with its own defaults (GridWorld needs discounting).
            self.hp = profile.default_hyperparameters()
        keep = built.meaning == self._built.meaning and built.n_actions == self._built.n_actions
        old_trainer = self.trainer
        self.env.close()
        self.env_id, self.env_kwargs, self.choices, self.profile = (
            new_id,
            kwargs,
            new_choices,
            profile,
        )
        self._install(built)
        if keep:
            self.trainer = self._new_trainer()
            self.trainer.adopt_progress(old_trainer)
            notice = "Env rebuilt; the agent is kept (observations mean the same)."
        else:
            self.agent = self._new_agent()
            self.trainer = self._new_trainer()
            notice = "Observations changed meaning, so the agent was reset."
        if built.skipped:
            notice += " Not applied: " + "; ".join(reason for _, reason in built.skipped)
        return RebuildReport(keep, notice, built.skipped)

    def reset_agent(self) -> None:
        """A fresh agent (same seed) and fresh statistics."""
        self.env.close()
        self._install(_build(self.env_id, self.env_kwargs, self.choices))
        self.agent = self._new_agent()
        self.trainer = self._new_trainer()

    def set_hyperparameters(self, hp: Hyperparameters) -> None:
        """New hyperparameters for the rest of the run (the table is kept)."""
        self.hp = hp
        self.agent.set_hyperparameters(hp)

    # --- seeing the table -------------------------------------------------
    def base_keys(self) -> list[Hashable] | None:
        """Table keys of the profile's base states, or None when wrappers hide them."""
        if self._base_keys is False:
            self._base_keys = self._compute_base_keys()
        return self._base_keys  # type: ignore[return-value]

    def _compute_base_keys(self) -> list[Hashable] | None:
        for choice in self.applied:
            spec = CATALOG[choice.name]
            if spec.changes_observation and choice.name not in STATELESS_OBSERVATION_WRAPPERS:
                return None
        layers = []
        env: Any = self.env
        while isinstance(env, gym.Wrapper):
            if isinstance(env, gym.ObservationWrapper):
                layers.append(env)
            env = env.env
        layers.reverse()  # innermost first
        keys = []
        for obs in self.profile.base_observations(self.env_kwargs):
            for layer in layers:
                obs = layer.observation(obs)
            keys.append(self.keyer.key(obs))
        return keys

    def hidden_reason(self) -> str:
        """Why heatmaps and the exact reference are unavailable (empty when they are)."""
        if self.base_keys() is not None:
            return ""
        names = [
            c.name
            for c in self.applied
            if CATALOG[c.name].changes_observation and c.name not in STATELESS_OBSERVATION_WRAPPERS
        ]
        return f"{', '.join(names)} makes observations depend on history; no per-state view"

    def base_q(self, snapshot: TrainingSnapshot | None = None) -> np.ndarray | None:
        """Q-values of the base states (from a snapshot, or the live agent)."""
        keys = self.base_keys()
        if keys is None:
            return None
        if snapshot is not None:
            return snapshot.values(keys)
        return self.agent.values(keys)

    def reference(self, snapshot: TrainingSnapshot | None = None) -> ReferenceMetrics | None:
        """The exact comparison of the greedy policy with the optimum."""
        q = self.base_q(snapshot)
        return None if q is None else self.profile.reference(q, self.env_kwargs, self.changes)

    def heatmaps(
        self, snapshot: TrainingSnapshot | None = None, focus: Any = None
    ) -> list[Heatmap] | None:
        q = self.base_q(snapshot)
        return None if q is None else self.profile.heatmaps(q, self.env_kwargs, focus,
                                                            self.changes)

    def agent_figures(self, snapshot: TrainingSnapshot | None = None) -> dict[str, float]:
        """Exact scoreboard figures of the agent's greedy policy (the live agent's, or a
        snapshot's) and of the optimum (`profile.agent_figures`); only the optimum's
        when wrappers hide the base states."""
        return self.profile.agent_figures(self.base_q(snapshot), self.env_kwargs, self.changes)

    def greedy_actions_for(
        self, observation: Any, snapshot: TrainingSnapshot | None = None
    ) -> tuple[tuple[int, ...], np.ndarray] | None:
        """What the agent's greedy policy does on an observation of this env (wrappers
        applied): every action tied for the best value, and the state's Q-values.

        Reads the live agent, or `snapshot` (e.g. the runner's latest while a child
        process trains). None when the agent has never updated that state (with a
        snapshot, which keeps no visit counts: when its values are all still 0), or
        the observation does not fit the env's space. Only reads the table, so it is
        safe while the trainer writes it on another thread.
        """
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
        except (IndexError, KeyError, TypeError, ValueError):  # a mismatched or moving table
            return None
        best = q.max()
        return tuple(int(a) for a in np.flatnonzero(q == best)), q

    # --- headless training ------------------------------------------------
    def train(
        self,
        target_gap: float | None = None,
        check_every: int = 10_000,
        chunk_seconds: float = 0.2,
        on_chunk: Callable[[TrainingSnapshot], None] | None = None,
    ) -> TrainOutcome:
        """Train to the end of the budget, or until the exact gap is at most `target_gap`.

        The gap is checked every `check_every` episodes (exactly, from the
        reference: no sampling noise). `on_chunk` sees a snapshot after each
        chunk of about `chunk_seconds`, e.g. to draw a progress bar.
        """
        if target_gap is not None:
            ref = self.reference()
            if ref is None or "gap" not in ref.figures:
                raise ValueError(f"--target-gap needs a game with an exact optimum; "
                                 f"{self.profile.title} has none here")
        trainer = self.trainer
        next_check = trainer.episodes + check_every
        gap = None
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
        if target_gap is not None:
            gap = self.reference().figures["gap"]  # type: ignore[union-attr]
            return TrainOutcome(gap <= target_gap, gap)
        return TrainOutcome(None, None)

    # --- evaluating, saving -----------------------------------------------
    def evaluate(
        self, episodes: int = 10_000, seed: int | None = None, progress=None
    ) -> EvalReport:
        """Greedy play on a fresh env; `seed` defaults to one derived from the session's."""
        env = self.make_env()
        try:
            eval_seed = self.seed + 1_000_003 if seed is None else seed
            return evaluate(
                env, self.agent, self.keyer, self.profile, episodes, eval_seed, progress
            )
        finally:
            env.close()

    def save(self, path: str | Path) -> Path:
        """Write the agent and everything needed to rebuild this session (atomically)."""
        from tui_gym.core.storage import save_session

        return save_session(self, path)

    @classmethod
    def load(cls, path: str | Path) -> Session:
        """A session rebuilt from a saved file; StorageError names the file when it cannot."""
        from tui_gym.core.storage import load_session

        return load_session(path)
