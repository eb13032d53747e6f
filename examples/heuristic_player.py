#!/usr/bin/env python3
"""A player for tui-gym's JSON-lines protocol: a Blackjack heuristic, plain Python.

It writes one request a line on its stdout and reads one answer a line on its
stdin, so `tui-gym benchmark` can run it:

    tui-gym benchmark blackjack --agent-cmd "python examples/heuristic_player.py"

In Blackjack it sticks on 17 or more and hits below; in any other game it
plays the first legal action. It stops when the benchmark says it is over
(or its input ends).
"""

import json
import sys


def ask(request):
    """Send one request and read its answer; end quietly when the other side is gone."""
    print(json.dumps(request), flush=True)
    line = sys.stdin.readline()
    if not line:
        raise SystemExit(0)
    return json.loads(line)


def choose(actions, answer):
    """Blackjack: stick on 17+, hit below. Otherwise the first legal action."""
    observation = answer["observation"]
    if "stick" in actions and "hit" in actions and isinstance(observation, list):
        return "stick" if observation[0] >= 17 else "hit"
    mask = answer.get("info", {}).get("action_mask")
    if isinstance(mask, list) and any(mask):
        return actions[mask.index(1)]
    return actions[0]


def main():
    actions = ask({"cmd": "spaces"})["actions"]
    while True:
        answer = ask({"cmd": "reset"})
        if "error" in answer:  # "the benchmark is over"
            return
        while not (answer["terminated"] or answer["truncated"]):
            answer = ask({"cmd": "step", "action": choose(actions, answer)})


if __name__ == "__main__":
    main()
