"""The bench's output: one table (each figure, its target, PASS or MISS) or one JSON object.

`_judged` walks every stage's result once: each row of the table, and the verdict of each
target, keyed like the JSON's figures, come from the same place.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from rich.table import Table

from tui_gym.bench import compare, dp, history, programs
from tui_gym.bench.figures import median
from tui_gym.bench.live import RUNNERS
from tui_gym.bench.run import BenchResults

if TYPE_CHECKING:
    from typing_extensions import TypeIs

PASS, MISS, UNDECIDED, MISSING, LESSON = "PASS", "MISS", "?", "n/a", "lesson"


@dataclass(frozen=True)
class Target:
    """A figure's target: `op` ("≤", "≥" or "<") `limit`, said as `text`."""

    op: str
    limit: float
    unit: str = ""
    shown: str = "g"  # the limit's format in the text

    @property
    def text(self) -> str:
        return f"{self.op} {self.limit:{self.shown}}{self.unit}"

    def verdict(self, value: float | None) -> str:
        """PASS or MISS, or MISSING for a figure not measured (None or NaN)."""
        if value is None or math.isnan(value):
            return MISSING
        good = {"≤": value <= self.limit, "≥": value >= self.limit, "<": value < self.limit}
        return PASS if good[self.op] else MISS


RSS_EPISODES = 2_000_000  # the RSS growth counts only over at least this many episodes
GAP_SPEEDUP = Target("≥", 50.0, "×")

_STYLE = {PASS: "[bold green]PASS[/]", MISS: "[bold red]MISS[/]", UNDECIDED: "[yellow]?[/]",
          MISSING: "[dim]n/a[/]", LESSON: "[dim]lesson[/]"}

Row = tuple[str, str, str, str]  # figure, measured, target, verdict ("" for none)


class _Judged:
    """The table's rows and the targets' verdicts, gathered stage by stage."""

    def __init__(self) -> None:
        self.rows: list[Row] = []
        self.verdicts: dict[str, str] = {}

    def row(self, label: str, measured: str, target: Target | str = "", key: str = "",
            value: float | None = None, verdict: str = "") -> None:
        """A row; with a `key`, its verdict: `verdict` if given, else `value` against
        `target`."""
        if key:
            assert isinstance(target, Target) or verdict
            self.verdicts[key] = verdict or target.verdict(value)  # type: ignore[union-attr]
        text = target.text if isinstance(target, Target) else target
        self.rows.append((label, measured, text, self.verdicts[key] if key else ""))

    def missing(self, *keys: str) -> None:
        """The verdicts of figures not measured."""
        self.verdicts.update(dict.fromkeys(keys, MISSING))

    def absent(self, found: object, *keys: str) -> TypeIs[None]:
        """Whether a stage's result is missing (its figures' verdicts then say so)."""
        if found is None:
            self.missing(*keys)
        return found is None

    def failed(self, label: str, text: str) -> None:
        self.rows.append((label, f"[red]{text}[/]", "", MISSING))


def _num(value: float | None, fmt: str, suffix: str = "") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{value:{fmt}}{suffix}"


def _judged(results: BenchResults) -> _Judged:
    """Every stage's rows and verdicts, in the table's order."""
    out = _Judged()
    found_compile = results.compile
    if not out.absent(found_compile, "cold_compile_s", "warm_load_s"):
        out.row("every learner compiled, empty cache", f"{found_compile.cold_s:.1f} s",
                Target("≤", 30.0, " s"), "cold_compile_s", found_compile.cold_s)
        out.row("  loaded from the cache", f"{found_compile.warm_s:.2f} s (importing Numba "
                f"{found_compile.import_s:.2f} s)", Target("≤", 1.0, " s"), "warm_load_s",
                found_compile.warm_s)
    for speed in results.speed or ():
        out.row(f"{speed.game}, {speed.algorithm}: ours ÷ tutorial loop",
                f"{_num(speed.speedup, ',.0f', '×')} ({_num(speed.episodes, ',.0f')} / "
                f"{_num(speed.tutorial_episodes, ',.0f')} ep/s)", Target("≥", 100.0, "×"),
                f"speedup[{speed.game}/{speed.algorithm}]", speed.speedup)
    for name, gap in results.gap.items():
        _gap_rows(out, name, gap)
    for runner in RUNNERS:
        _live_rows(out, results, runner)
    memory = results.memory
    if not out.absent(memory, "rss_growth_mb"):  # a run shorter than RSS_EPISODES misses
        out.row(f"RSS growth over {memory.episodes:,} ep ({memory.engine})",
                f"{memory.growth_mb:+.1f} MB", Target("<", 20.0, " MB"), "rss_growth_mb",
                memory.growth_mb if memory.episodes >= RSS_EPISODES else math.inf)
    startup = results.startup
    if not out.absent(startup, "startup_s"):
        samples = ", ".join(f"{s:.2f}" for s in startup.samples)
        out.row("start to first frame", f"{startup.seconds:.2f} s ({samples})",
                Target("≤", 1.0, " s"), "startup_s", startup.seconds)
    for edit in results.map_edit or ():
        out.row(f"{edit.game}: map edit → new optimum, {edit.size} (median, worst of "
                f"{edit.edits})", f"{edit.median_ms:.0f} ms (worst {edit.worst_ms:.0f})",
                Target("≤", 50.0, " ms"), f"map_edit_ms[{edit.game}]", edit.median_ms)
    _planning_rows(out, results)
    _programs_rows(out, results.programs)
    _seeds_rows(out, results)
    for found in results.defaults or ():
        out.row(f"{found.game}, {found.algorithm}: defaults at the bound",
                f"{found.met} of {found.seeds} (worst {found.worst:.4g}; {found.bound})",
                Target("≥", 0.95, shown=".0%"), f"defaults[{found.game}/{found.algorithm}]",
                found.share, LESSON if found.lesson else "")
    _history_rows(out, results.history)
    _tasks_rows(out, results.tasks)
    _dp_rows(out, results.dp)
    out.missing(*(key for stage, key in (("speed", "speedup"), ("defaults", "defaults"),
                                         ("map_edit", "map_edit_ms")) if stage in results.errors))
    for stage, error in results.errors.items():
        out.failed(f"{stage} failed", error)
    return out


def _gap_rows(out: _Judged, name: str, gap: Any) -> None:
    if gap.speedup is None:
        verdict = MISSING
    elif not gap.reached:
        verdict = MISS
    elif gap.speedup >= GAP_SPEEDUP.limit:
        verdict = PASS  # a lower bound above the target decides it too
    else:
        verdict = MISS if gap.tutorial_reached else UNDECIDED
    ours_eps = sorted(r.episodes for r in gap.ours)
    mark = "" if gap.reached else " (not reached)"
    out.row(f"{gap.title}: time to gap ≤ {gap.target:.4g}, ours",
            f"{_num(gap.time_to_gap_s, '.2f', ' s')}{mark}, {ours_eps[len(ours_eps) // 2]:,} ep")
    theirs_eps = sorted(r.episodes for r in gap.tutorial)
    prefix = "" if gap.tutorial_reached else "≥ "
    mark = "" if gap.tutorial_reached else " (capped)"
    out.row("  tutorial loop", f"{prefix}{_num(gap.tutorial_time_to_gap_s, '.1f', ' s')}{mark}, "
            f"{theirs_eps[len(theirs_eps) // 2]:,} ep" if theirs_eps else "n/a")
    out.row("  tutorial time / ours", prefix + _num(gap.speedup, ".0f", "×"), GAP_SPEEDUP,
            f"time_to_gap[{name}]", verdict=verdict)


def _live_rows(out: _Judged, results: BenchResults, runner: str) -> None:
    name = f"{runner} runner" + (" (default)" if runner == results.default_runner else "")
    live = results.live_for(runner)
    if live is None:
        failed = results.live.get(runner)
        out.missing(*(f"{key}[{runner}]" for key in ("live_ratio", "ui_refresh_hz",
                                                     "key_latency_p95_ms")))
        out.failed(f"live, {name}", "; ".join(failed.errors) if failed is not None
                   else "not measured")
        return
    out.row(f"live ep/s ÷ headless, {name}",
            f"{live.live_ratio:.2f} ({live.live_eps:,.0f} / {live.headless_eps:,.0f})",
            Target("≥", 0.8, shown=".2f"), f"live_ratio[{runner}]", live.live_ratio)
    out.row(f"  snapshots drawn, {runner}", f"{live.refresh_hz:.1f} Hz", Target("≥", 10.0, " Hz"),
            f"ui_refresh_hz[{runner}]", live.refresh_hz)
    p95 = live.key_latency_ms(95)
    out.row(f"  key → screen p95, {runner}", f"{p95:.0f} ms (p50 "
            f"{live.key_latency_ms(50):.0f}, n={live.presses})", Target("≤", 50.0, " ms"),
            f"key_latency_p95_ms[{runner}]", p95)


def _planning_rows(out: _Judged, results: BenchResults) -> None:
    planning = results.planning
    if out.absent(planning, "planning"):
        return
    fewer = planning.dyna_q_episodes < planning.q_learning_episodes
    verdict = PASS if fewer and all(r.reached for r in planning.dyna_q) else MISS

    def runs(items: tuple) -> str:
        return _num(median([r.episodes for r in items]), ",.0f") + (
            "" if all(r.reached for r in items) else " (not all reached)")

    out.row(f"real episodes to ≤ {planning.bound:g} on {planning.game}: Q-learning / Dyna-Q",
            f"{runs(planning.q_learning)} / {runs(planning.dyna_q)}", "Dyna-Q fewer",
            "planning", verdict=verdict)


def _programs_rows(out: _Judged, found: programs.ProgramsResult | None) -> None:
    if out.absent(found, "regret_separation_ratio", "protocol_steps_per_second",
                  "mcp_steps_per_second"):
        return
    sep = found.separation
    out.row("episodes to separate optimal from 5% deviations, by return",
            f"{_num(sep.by_return, ',.0f')}")
    out.row("  by exact regret", f"{_num(sep.by_regret, ',.0f')}")
    out.row("  ratio", _num(sep.ratio, ".0f", "×"), Target("≥", 10.0, "×"),
            "regret_separation_ratio", sep.ratio)
    rate = found.protocol.steps_per_second
    out.row(f"protocol over a pipe, steps/s, {programs.WINDOW} requests in flight",
            _num(rate, ",.0f"), Target("≥", 20_000.0, shown=",.0f"), "protocol_steps_per_second",
            rate)
    trip = found.protocol_round_trip
    if trip.round_trips:
        out.row("  one request at a time, round trip p50",
                f"{_num(trip.p50_us, '.0f', ' µs')} (p95 {_num(trip.p95_us, '.0f')}; "
                f"{_num(trip.rate.steps_per_second, ',.0f')} steps/s)")
    rate = found.mcp_together.steps_per_second
    if found.mcp_together.reason:
        out.missing("mcp_steps_per_second")
        out.rows.append(("MCP, steps/s", f"[dim]{found.mcp_together.reason}[/]", "", MISSING))
    else:
        out.row(f"MCP, steps/s, {programs.MCP_GAMES} games at once", _num(rate, ",.0f"),
                Target("≥", 1_000.0, shown=",.0f"), "mcp_steps_per_second", rate)
        out.row("  one call at a time", _num(found.mcp_one.steps_per_second, ",.0f"))


def _seeds_rows(out: _Judged, results: BenchResults) -> None:
    found = results.seeds
    if out.absent(found, "compare_speedup", "example_6_6"):
        return
    scaled = ("" if found.tutorial_learners == found.learners else
              f", {found.tutorial_learners} of {found.learners} run, scaled")
    out.row(f"compare on {found.game}, {found.seeds} seeds × {found.episodes} ep: tutorial "
            "loop ÷ compare", f"{_num(found.speedup, '.1f', '×')} ({found.tutorial_s:.1f} s"
            f"{scaled} / {found.compare_s:.2f} s)", Target("≥", 100.0, "×"), "compare_speedup",
            found.speedup)
    online = found.online_returns
    if len(online) != 2:
        out.missing("example_6_6")
        return
    out.row("  Example 6.6: mean online return, Q-learning / SARSA",
            f"{online[0]:+.1f} / {online[1]:+.1f}", "SARSA above", "example_6_6",
            verdict=MISSING if math.isnan(online[1]) else PASS if online[1] > online[0] else MISS)


def _history_rows(out: _Judged, found: history.HistoryResult | None) -> None:
    if out.absent(found, "history_overhead", "history_bytes_per_1000_runs"):
        return
    out.row(f"run history: recording's share of a train {found.game} run",
            f"{found.overhead:.2%} (median of {len(found.shares)})", Target("≤", 0.02, shown=".0%"),
            "history_overhead", found.overhead)
    out.row("  whole run, fastest recorded ÷ fastest --no-record (noisy)",
            f"{found.ab_ratio:.3f} ({min(found.recorded_s):.2f} s / "
            f"{min(found.unrecorded_s):.2f} s)")
    out.row(f"run history: file size per 1,000 default runs ({found.runs:,} written)",
            f"{found.bytes_per_1000 / 1e6:.3f} MB", Target("<", 1.0, " MB"),
            "history_bytes_per_1000_runs", found.bytes_per_1000 / 1e6)


def _tasks_rows(out: _Judged, found: compare.TasksResult | None) -> None:
    if out.absent(found, "task_split_overhead", "cluster_throughput_share"):
        return
    split, share = found.split_overhead, found.cluster_share
    out.row(f"compare on {found.game}, {found.seeds} seeds: {found.tasks} tasks, recorded "
            "÷ one batch", "n/a" if split is None else
            f"{split:.3f} ({found.tasks_s:.2f} s / {found.batch_s:.2f} s)", Target("≤", 1.10),
            "task_split_overhead", split)
    target = Target("≥", 0.8)  # the cluster's throughput ÷ the local executor's
    workers = f"LocalCluster({compare.CLUSTER_WORKERS}) ÷ local executor, throughput"
    if share is None:
        out.missing("cluster_throughput_share")
        out.row(workers, found.cluster_note or "n/a", target)
    else:
        out.row(f"{workers}, sweep of {len(compare.SWEEP_RATES)} points",
                f"{share:.3f} ({found.local_s:.2f} s / {found.cluster_s:.2f} s)", target,
                "cluster_throughput_share", share)


def _dp_rows(out: _Judged, found: dp.DPResult | None) -> None:
    if out.absent(found, "taxi_sweep_ms", "jack_policy_iteration_s", "plan_view"):
        return
    out.row("planning: a value-iteration sweep on Taxi (500 × 6), median",
            f"{found.taxi_sweep_ms:.2f} ms", Target("≤", 5.0, " ms"), "taxi_sweep_ms",
            found.taxi_sweep_ms)
    out.row("  Jack's car rental by policy iteration (Figure 4.2), median",
            f"{found.jack_seconds:.2f} s (model built once: {found.jack_model_seconds:.2f} s)",
            Target("≤", 1.0, " s"), "jack_policy_iteration_s", found.jack_seconds)
    for view in found.views:
        out.row(f"  Plan view on {view.game}: sweeps drawn a second (50/s asked)",
                f"{view.sweeps_per_second:.1f}", Target("≥", 20.0),
                f"plan_sweeps_per_second[{view.game}]", view.sweeps_per_second)
        out.row(f"  Plan view on {view.game}: key → screen p95 while it runs",
                f"{view.key_p95_ms:.0f} ms (p50 {median(list(view.keys_ms)):.0f}, "
                f"n={len(view.keys_ms)})", Target("≤", 50.0, " ms"),
                f"plan_key_p95_ms[{view.game}]", view.key_p95_ms)


def verdicts(results: BenchResults) -> dict[str, str]:
    """Each target's verdict, keyed like the JSON's figures."""
    return _judged(results).verdicts


# --- JSON ---------------------------------------------------------------------
def _of(found: Any, **names: str) -> dict[str, Any]:
    """`found`'s attributes under the given keys (each None when `found` is None)."""
    return {key: getattr(found, name, None) for key, name in names.items()}


def _game_dict(results: BenchResults, name: str) -> dict[str, Any]:
    gap = results.gap.get(name)
    return {
        "title": getattr(gap, "title", name),
        **_of(gap, target_gap="target", time_to_gap_s="time_to_gap_s",
              time_to_gap_reached="reached", tutorial_time_to_gap_s="tutorial_time_to_gap_s",
              tutorial_reached="tutorial_reached", time_to_gap_speedup="speedup"),
        "time_to_gap_episodes": gap and [r.episodes for r in gap.ours],
        "tutorial_time_to_gap_episodes": gap and [r.episodes for r in gap.tutorial],
        "time_to_gap_speedup_is_lower_bound": gap and not gap.tutorial_reached,
        "speed": [
            {"algorithm": s.algorithm, "episodes_per_second": s.episodes,
             "tutorial_episodes_per_second": s.tutorial_episodes, "speedup": s.speedup,
             "steps_per_second": s.steps, "tutorial_steps_per_second": s.tutorial_steps}
            for s in results.speed or () if s.game == name
        ],
        "defaults": [{**asdict(d), "share": d.share, "lesson": d.lesson or None}
                     for d in results.defaults or () if d.game == name],
    }


def _json(found: Any) -> Any:
    """A stage's JSON object, or None for a stage that did not run."""
    return None if found is None else found.to_json()


def to_json(results: BenchResults) -> dict[str, Any]:
    """The JSON object `tui-gym bench --json` prints (NaN and missing figures are null).

    `games` holds every game's figures; the top-level throughput and gap figures are
    those of the first game measured."""
    names = list(dict.fromkeys([*(x.game for x in results.speed or ()), *results.gap,
                                *(d.game for d in results.defaults or ())]))
    default, machine = results.live_for(results.default_runner), results.machine
    return {
        "quick": results.quick,
        "seconds": results.seconds,
        "machine": {"cpus": machine.cpus, "load_average_before": machine.load_before,
                    "load_average_after": machine.load_after},
        **_of(results.compile, cold_compile_s="cold_s", numba_import_s="import_s",
              warm_load_s="warm_s"),
        **{key: value for key, value in _game_dict(results, next(iter(results.gap), "")).items()
           if key not in ("title", "speed", "defaults")},
        "games": {name: _game_dict(results, name) for name in names},
        "default_runner": results.default_runner,
        **_of(default, live_ratio="live_ratio", ui_refresh_hz="refresh_hz"),
        "key_latency_p50_ms": default and default.key_latency_ms(50),
        "key_latency_p95_ms": default and default.key_latency_ms(95),
        "runners": {runner: results.live[runner].to_json() if runner in results.live
                    else {"error": "not measured"} for runner in RUNNERS},
        "rss_growth_mb": getattr(results.memory, "growth_mb", None),
        "rss": _json(results.memory),
        "startup_s": getattr(results.startup, "seconds", None),
        "startup_samples_s": getattr(results.startup, "samples", None),
        "planning": _json(results.planning),
        "programs": _json(results.programs),
        "map_edit": [asdict(edit) for edit in results.map_edit or ()],
        "history": _json(results.history),
        "tasks": _json(results.tasks),
        "compare": _json(results.seeds),
        "planning_dp": _json(results.dp),
        "verdicts": verdicts(results),
        "errors": dict(results.errors),
    }


def table(results: BenchResults) -> Table:
    """Every figure beside its target and verdict."""
    machine = results.machine
    load = ""
    if machine.load_before and machine.load_after:
        load = (f"; load average {machine.load_before[0]:.2f} before, "
                f"{machine.load_after[0]:.2f} after")
    out = Table(title=f"tui-gym bench ({'quick' if results.quick else 'full'}, "
                f"{results.seconds:.0f} s, {machine.cpus or '?'} CPUs{load})",
                title_justify="left")
    out.add_column("figure", style="bold")
    out.add_column("measured", justify="right")
    out.add_column("target", justify="right")
    out.add_column("", justify="center")
    for label, measured, target, verdict in _judged(results).rows:
        out.add_row(label, measured, target, _STYLE[verdict] if verdict else "")
    return out


def notes(results: BenchResults) -> list[str]:
    """Lines to print under the table: what the figures are, and any lower bounds."""
    lines = ["Ratios are taken between figures measured in this run; speeds are medians over "
             "repeats, key latency percentiles over all presses."]
    verdict, default = verdicts(results), results.default_runner
    if verdict.get(f"live_ratio[{default}]") == PASS and any(
            verdict.get(f"live_ratio[{r}]") == MISS for r in RUNNERS if r != default):
        lines.append(f"The app trains with the {default} runner; the others are measured for "
                     "comparison (a thread runner shares one interpreter lock with the UI, so "
                     "the UI's drawing comes out of training time).")
    if results.planning is not None:
        lines.append(f"Planning: the bound is on the {results.planning.measure}; episodes are "
                     "real ones (Dyna-Q's simulated updates are not counted), medians over seeds.")
    capped = [gap.title for gap in results.gap.values() if not gap.tutorial_reached]
    if capped:
        lines.append(f"The tutorial loop was stopped by its time cap before reaching the gap on "
                     f"{', '.join(capped)}: its time and the speed-up are lower bounds (run "
                     "without --quick for longer caps).")
    if results.programs is not None:
        sep = results.programs.separation
        lines.append(f"Episodes to separate: each player played {sep.episodes:,} Blackjack "
                     "episodes on the same seeds; n = 1.96² (sd_a² + sd_b²) / Δ² episodes each, "
                     f"Δ the deviating player's mean exact regret ({sep.delta:.4f}), sd the "
                     f"measured per-episode standard deviations (return {sep.return_sd[1]:.3f}, "
                     f"regret {sep.regret_sd[1]:.3f}).")
    load, cpus = results.machine.load_before, results.machine.cpus or 1
    if load is not None and load[0] > 0.5 * cpus:
        lines.append(f"Load average {load[0]:.2f} on {cpus} CPUs when the run started (other "
                     "work, or a run just before): absolute speeds may be low; ratios are less "
                     "affected.")
    return lines
