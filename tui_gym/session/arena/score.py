"""A player's score beside the exact optimum: returns, exact decision regret, agreement."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from tui_gym.session.play import Tally

RECENT_EPISODES = 100  # episodes listed one by one in a score; older ones only count
NO_VALUES = "the game's hint names optimal actions but gives no exact action values"
NOT_EXACT = "the wrappers change the game beyond its exact figures"


@dataclass(frozen=True)
class Verdict:
    """One move judged against the exact optimum before it was made: `decision` False where
    the optimum had no say; `regret` None without exact action values (`note` says why)."""

    decision: bool
    agreed: bool | None = None
    regret: float | None = None
    optimal: tuple[str, ...] = ()
    values: dict[str, float] | None = None
    note: str = ""

    @classmethod
    def from_hint(cls, hint: dict[str, Any], action: str) -> Verdict:
        """Judge `action` (its name) from a protocol hint answer for the state it was taken in."""
        optimal = tuple(hint.get("optimal_actions") or ())
        values = hint.get("action_values")
        if not optimal:
            if hint.get("unwrapped_optimal_actions"):  # the wrappers change the game
                return cls(False, note=NOT_EXACT)
            return cls(False)
        if not isinstance(values, dict) or action not in values:
            return cls(True, action in optimal, None, optimal, None, NO_VALUES)
        finite = [float(v) for v in values.values() if math.isfinite(v)]
        mine = float(values[action])
        regret = max(0.0, max(finite) - mine) if finite and math.isfinite(mine) else None
        if regret is not None and action in optimal:
            regret = 0.0  # an optimal move gives nothing up (ties differ by round-off only)
        return cls(True, action in optimal, regret, optimal, dict(values),
                   "" if regret is not None else "the action values are not finite here")

    def to_json(self) -> dict[str, Any]:
        data: dict[str, Any] = {"decision": self.decision}
        if self.decision:
            data["optimal"] = self.agreed
            data["optimal_actions"] = list(self.optimal)
            data["regret"] = self.regret
        if self.note:
            data["note"] = self.note
        return data


@dataclass
class EpisodeScore:
    """One episode: its seed, return, steps, decisions and exact regret so far."""

    index: int  # 1-based
    seed: int | None
    episode_return: float = 0.0
    steps: int = 0
    decisions: int = 0
    agreed: int = 0
    regret: float = 0.0
    unscored: int = 0  # decisions with no exact action values (the regret then is unknown)
    unjudged: int = 0  # moves the optimum could not judge (the wrappers change the game)
    done: bool = False
    terminated: bool = False

    @property
    def exact_regret(self) -> float | None:
        """The episode's summed regret; None if a move could not be scored exactly."""
        return None if self.unscored or self.unjudged else self.regret

    def to_json(self) -> dict[str, Any]:
        return {
            "episode": self.index, "seed": self.seed, "return": self.episode_return,
            "steps": self.steps, "decisions": self.decisions, "agreed": self.agreed,
            "regret": self.exact_regret, "done": self.done,
        }


@dataclass
class ArenaScore:
    """Returns, exact decision regret and agreement of one player on one game; the totals
    count finished episodes, the running one is kept apart (`current`)."""

    current: EpisodeScore | None = None
    returns: Tally = field(default_factory=Tally)  # of the finished episodes
    regrets: Tally = field(default_factory=Tally)  # of those with an exact regret
    decisions: int = 0
    agreed: int = 0
    unscored: int = 0
    unjudged: int = 0
    notes: set[str] = field(default_factory=set)
    recent: deque[EpisodeScore] = field(default_factory=lambda: deque(maxlen=RECENT_EPISODES))
    history: list[EpisodeScore] | None = None  # every finished episode, when a list is given

    @property
    def finished(self) -> int:
        return self.returns.episodes

    def start_episode(self, seed: int | None) -> None:
        """A new episode begins (one left unfinished is dropped from the totals)."""
        index = self.finished + 1
        self.current = EpisodeScore(index, seed)

    def record(self, verdict: Verdict, reward: float, done: bool, terminated: bool) -> None:
        """One move of the current episode: its verdict and the reward it earned."""
        episode = self.current
        if episode is None or episode.done:
            raise ValueError("no episode running")
        episode.steps += 1
        episode.episode_return += float(reward)
        if verdict.decision:
            episode.decisions += 1
            episode.agreed += bool(verdict.agreed)
            if verdict.regret is None:
                episode.unscored += 1
            else:
                episode.regret += verdict.regret
        elif verdict.note:  # not a decision because the optimum is not known here
            episode.unjudged += 1
        if verdict.note and len(self.notes) < 8:
            self.notes.add(verdict.note)
        if done:
            self._finish(episode, terminated)

    def _finish(self, episode: EpisodeScore, terminated: bool) -> None:
        episode.done = True
        episode.terminated = terminated
        self.returns.add(episode.episode_return)
        self.decisions += episode.decisions
        self.agreed += episode.agreed
        self.unscored += episode.unscored
        self.unjudged += episode.unjudged
        if episode.exact_regret is not None:
            self.regrets.add(episode.regret)
        self.recent.append(episode)
        if self.history is not None:
            self.history.append(episode)

    @property
    def mean_return(self) -> float | None:
        return self.returns.mean if self.returns.episodes else None

    @property
    def mean_regret(self) -> float | None:
        return self.regrets.mean if self.regrets.episodes else None

    @property
    def agreement(self) -> float | None:
        return self.agreed / self.decisions if self.decisions else None

    def to_json(self, *, running: bool = True) -> dict[str, Any]:
        """The score as JSON data, the running episode's own figures too unless not `running`."""
        why = "; ".join(sorted(self.notes))
        regret_note = ""
        if self.unscored:
            regret_note = f"regret unavailable for {self.unscored} of {self.decisions} decisions"
        elif self.unjudged:
            moves = "1 move" if self.unjudged == 1 else f"{self.unjudged} moves"
            regret_note = f"regret unavailable: {moves} could not be judged"
        if regret_note and why:
            regret_note += f": {why}"
        data: dict[str, Any] = {
            "episodes": self.finished, "mean_return": self.mean_return,
            "return_ci95": self.returns.half_width(),
            "regret": {
                "mean_per_episode": self.mean_regret, "ci95": self.regrets.half_width(),
                "total": self.regrets.total if self.regrets.episodes else None,
                "episodes": self.regrets.episodes, "unit": "expected return lost to the optimum",
                "note": regret_note,
            },
            "decisions": self.decisions, "agreed": self.agreed, "agreement": self.agreement,
            "recent_episodes": [e.to_json() for e in self.recent],
        }
        if running and self.current is not None and not self.current.done:
            data["current_episode"] = self.current.to_json()
        return data
