"""The baseline: a tutorial-style loop on the game's own Gymnasium env, the rule uncompiled."""

from __future__ import annotations

import json
import pickle
import sys
import time
from collections.abc import Sequence
from typing import Any

from tui_gym.bench.figures import child_json

TASK_TIMEOUT_S = 3600.0  # the whole process, at most
WARMUP_S = 0.05


def play(session: Any, episodes: int | None = None, seconds: float | None = None) -> int:
    """Train the session's agent on its env in the tutorial's loop: `episodes`, or until
    `seconds` pass (checked every step); the steps taken."""
    env, keyer, agent = session.env, session.keyer, session.agent
    end = time.perf_counter() + seconds if seconds is not None else None
    steps = played = 0
    while episodes is None or played < episodes:
        obs, _ = env.reset()
        state = keyer.key(obs)
        action = agent.act(state)
        while True:
            obs, reward, terminated, truncated, _ = env.step(action)
            after = keyer.key(obs)
            chosen, _ = agent.learn(state, action, float(reward), after, terminated, truncated)
            steps += 1
            if end is not None and time.perf_counter() >= end:
                return steps
            if terminated or truncated:
                break
            state, action = after, chosen if chosen >= 0 else agent.act(after)
        agent.end_episodes(1)
        agent.begin_episode()
        played += 1
    return steps


def _session(game: str, algorithm: str, hp: dict[str, Any], seed: int,
             kwargs: dict[str, Any] | None = None) -> Any:
    from tui_gym.session.session import Session

    session = Session(game, kwargs, algorithm=algorithm, hp=hp, seed=seed, engine="env")
    session.env.reset(seed=seed)
    return session


def _run(task: dict[str, Any]) -> dict[str, Any]:
    kind = task["kind"]
    if kind == "rate":
        session = _session(task["game"], task["algorithm"], task["hp"], task["seed"])
        if task.get("learner"):  # the bench's own file: the learner to go on from
            with open(task["learner"], "rb") as file:
                session.agent.load_state(pickle.load(file))
        play(session, seconds=WARMUP_S)  # first calls (imports, tables) off the clock
        first, began = session.agent.episode, time.perf_counter()
        steps = play(session, seconds=task["seconds"])
        elapsed = time.perf_counter() - began
        return {"steps_per_second": steps / elapsed, "episodes": session.agent.episode - first,
                "seconds": elapsed}
    if kind == "gap":
        began = time.perf_counter()
        session = _session(task["game"], "q-learning", task["hp"], task["seed"], task["kwargs"])
        budget, gap = session.hp.episodes, float("inf")
        while session.agent.episode < budget:
            play(session, min(task["check_every"], budget - session.agent.episode))
            gap = session.reference().figures["gap"]
            if gap <= task["target"] or time.perf_counter() - began >= task["cap"]:
                break
        return {"seconds": time.perf_counter() - began, "episodes": session.agent.episode,
                "gap": gap, "reached": gap <= task["target"]}
    began = time.perf_counter()
    for algorithm in task["algorithms"]:
        for seed in range(task["seeds"]):
            play(_session(task["game"], algorithm, task["hp"], seed), task["episodes"])
    return {"seconds": time.perf_counter() - began}


def measure(tasks: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Run `tasks` in a process where nothing is compiled; their answers, in order."""
    return list(child_json("tui_gym.bench.tutorial", what="the tutorial loop",
                           timeout=TASK_TIMEOUT_S, stdin=json.dumps(list(tasks)),
                           env={"NUMBA_DISABLE_JIT": "1"}))


if __name__ == "__main__":
    print(json.dumps([_run(task) for task in json.loads(sys.stdin.read())]))
