"""Benchmarks behind `tui-gym bench`: they print figures, never assert.

Speeds are quoted as ratios against a baseline measured in the same run (the
machine is small and shared), each figure a median over repeats.

- `tutorial`: the baseline, a tutorial-style loop on a game's own Gymnasium
  env calling the algorithm's own rule uncompiled.
- `compiling`: every learner compiled with an empty cache, then loaded.
- `speed`: every algorithm's training speed on every game with `bench_kwargs`,
  against the tutorial loop.
- `gap`: time to a greedy policy within the game's target gap of the optimum,
  ours (as `tui-gym train GAME --target-gap G`) against the tutorial loop.
- `learners`: Dyna-Q's planning against Q-learning, in real episodes.
- `seeds`: `compare` against the same learners one after another.
- `defaults`: the share of seeds the defaults bring to the game's bound.
- `live`: episodes/s while the real app shows training at max speed, against
  headless; how often the Train view draws; key press to screen latency;
  for the thread and the process runner.
- `memory`: RSS growth over 2,000,000 training episodes.
- `startup`: launching `python -m tui_gym` to its first frame on a terminal.
- `figures`: medians, percentiles, ratios, the machine's load.
- `results`: `BenchResults`, what one run found.
- `report`: the table (figure, target, PASS/MISS) and the JSON object.
- `run`: `run_bench(quick)`, every stage with the quick or the full plan.
"""
