"""`tui-gym benchmark`: a player against the exact optimum on fixed seeds.

- `referee`: `Referee`, the game as a benchmark serves it to a player (episode
  i on seed S+i, hints refused, an invalid action replaced by the default);
- `players`: the players: `random`, `optimal`, a saved agent, and any program
  that speaks the JSON-lines protocol (time limit per decision, crashes and
  hangs handled);
- `results`: `BenchmarkResult`, its figures with 95% intervals, as text or JSON;
- `leaderboard`: recording results in the run history and listing them best first;
- `command`: the sub-command's flags and what it prints.

The default action, played for a player whose action is invalid or late, is
the first legal action (action 0 where every action is legal).
"""
