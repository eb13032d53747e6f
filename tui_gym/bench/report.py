"""The bench's output: one table (each figure, its target, PASS or MISS) or one JSON object,
both from one walk over the stages' results (`_judged`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

from rich.table import Table

from tui_gym.bench import compare, dp, history, programs
from tui_gym.bench.figures import median, percentile, ratio
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


class _Judged:
    """The figures of a run, stage by stage: the table's rows, the JSON's values and the
    targets' verdicts, each figure under one key."""

    def __init__(self) -> None:
        self.rows: list[tuple[str, str, str, str]] = []  # label, measured, target, verdict
        self.values: dict[str, Any] = {}
        self.verdicts: dict[str, str] = {}

    def row(self, key: str, label: str, measured: str, value: Any = None,
            target: Target | str = "", verdict: str = "") -> None:
        """A figure; with a `Target` (or a `verdict`), its verdict: `verdict` if given, else
        `value` against the target."""
        self.values[key] = value
        if isinstance(target, Target):
            verdict = verdict or target.verdict(value)
        if verdict:
            self.verdicts[key] = verdict
        text = target.text if isinstance(target, Target) else target
        self.rows.append((label, measured, text, verdict))

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
    """Every stage's figures, in the table's order."""
    out = _Judged()
    found_compile = results.compile
    if not out.absent(found_compile, "cold_compile_s", "warm_load_s"):
        out.row("cold_compile_s", "every learner compiled, empty cache",
                f"{found_compile.cold_s:.1f} s", found_compile.cold_s, Target("≤", 30.0, " s"))
        out.row("warm_load_s", "  loaded from the cache", f"{found_compile.warm_s:.2f} s "
                f"(importing Numba {found_compile.import_s:.2f} s)", found_compile.warm_s,
                Target("≤", 1.0, " s"))
    for speed in results.speed or ():
        speedup, length = ratio(speed.steps, speed.tutorial_steps), max(speed.mean_length, 1.0)
        out.row(f"speedup[{speed.game}/{speed.algorithm}]",
                f"{speed.game}, {speed.algorithm}: ours ÷ tutorial loop",
                f"{_num(speedup, ',.0f', '×')} ({_num(speed.steps / length, ',.0f')} / "
                f"{_num(speed.tutorial_steps / length, ',.0f')} ep/s)", speedup,
                Target("≥", 100.0, "×"))
    for name, gap in results.gap.items():
        _gap_rows(out, name, gap)
    for runner in RUNNERS:
        _live_rows(out, results, runner)
    memory = results.memory
    if not out.absent(memory, "rss_growth_mb"):  # a run shorter than RSS_EPISODES misses
        growth = memory.rss_end_mb - memory.rss_start_mb
        out.row("rss_growth_mb", f"RSS growth over {memory.episodes:,} ep ({memory.engine})",
                f"{growth:+.1f} MB", growth, Target("<", 20.0, " MB"),
                "" if memory.episodes >= RSS_EPISODES else MISS)
    startup = results.startup
    if not out.absent(startup, "startup_s"):
        samples = ", ".join(f"{s:.2f}" for s in startup.samples)
        seconds = median(startup.samples)
        out.row("startup_s", "start to first frame", f"{seconds:.2f} s ({samples})", seconds,
                Target("≤", 1.0, " s"))
    _parts_rows(out, results)
    for edit in results.map_edit or ():
        out.row(f"map_edit_ms[{edit.game}]", f"{edit.game}: map edit → new optimum, "
                f"{edit.size} (median, worst of {edit.edits})",
                f"{edit.median_ms:.0f} ms (worst {edit.worst_ms:.0f})", edit.median_ms,
                Target("≤", 50.0, " ms"))
    _planning_rows(out, results)
    _programs_rows(out, results.programs)
    _seeds_rows(out, results)
    for found in results.defaults or ():
        target = Target("≥", 0.95, shown=".0%")
        short = found.lesson and target.verdict(found.share) == MISS  # a lesson only when short
        out.row(f"defaults[{found.game}/{found.algorithm}]",
                f"{found.game}, {found.algorithm}: defaults at the bound",
                f"{found.met} of {found.seeds} (worst {found.worst:.4g}; {found.bound})",
                found.share, target, LESSON if short else "")
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
    out.row(f"time_to_gap_s[{name}]", f"{gap.title}: time to gap ≤ {gap.target:.4g}, ours",
            f"{_num(gap.time_to_gap_s, '.2f', ' s')}{mark}, {ours_eps[len(ours_eps) // 2]:,} ep",
            gap.time_to_gap_s)
    theirs_eps = sorted(r.episodes for r in gap.tutorial)
    prefix = "" if gap.tutorial_reached else "≥ "
    mark = "" if gap.tutorial_reached else " (capped)"
    out.row(f"tutorial_time_to_gap_s[{name}]", "  tutorial loop",
            f"{prefix}{_num(gap.tutorial_time_to_gap_s, '.1f', ' s')}{mark}, "
            f"{theirs_eps[len(theirs_eps) // 2]:,} ep" if theirs_eps else "n/a",
            gap.tutorial_time_to_gap_s)
    out.row(f"time_to_gap[{name}]", "  tutorial time / ours",
            prefix + _num(gap.speedup, ".0f", "×"), gap.speedup, GAP_SPEEDUP, verdict)


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
    out.row(f"live_ratio[{runner}]", f"live ep/s ÷ headless, {name}",
            f"{live.live_ratio:.2f} ({live.live_eps:,.0f} / {live.headless_eps:,.0f})",
            live.live_ratio, Target("≥", 0.8, shown=".2f"))
    out.row(f"ui_refresh_hz[{runner}]", f"  snapshots drawn, {runner}",
            f"{live.refresh_hz:.1f} Hz", live.refresh_hz, Target("≥", 10.0, " Hz"))
    p95 = live.key_latency_ms(95)
    out.row(f"key_latency_p95_ms[{runner}]", f"  key → screen p95, {runner}",
            f"{p95:.0f} ms (p50 {live.key_latency_ms(50):.0f}, n={live.presses})", p95,
            Target("≤", 50.0, " ms"))


def _parts_rows(out: _Judged, results: BenchResults) -> None:
    """Each speed part left to Textual, beside the figures with every part in use."""
    ours, launched = results.live_for(results.default_runner), results.startup
    p95 = ours.key_latency_ms(95) if ours is not None else None
    start = median(launched.samples) if launched is not None else None
    for part in results.parts or ():
        out.row(f"stock_key_p95_ms[{part.part}]", f"  Textual's own {part.part}: key → screen p95",
                f"{part.key_p95_ms:.0f} ms (p50 {part.key_p50_ms:.0f}; "
                f"ours {_num(p95, '.0f', ' ms')})", part.key_p95_ms)
        out.row(f"stock_startup_s[{part.part}]", "    start to first frame",
                f"{part.startup_s:.2f} s (ours {_num(start, '.2f', ' s')})", part.startup_s)


def _planning_rows(out: _Judged, results: BenchResults) -> None:
    planning = results.planning
    if out.absent(planning, "planning"):
        return
    both = (planning.q_learning, planning.dyna_q)
    episodes = [median([r.episodes for r in runs]) for runs in both]
    reached = [all(r.reached for r in runs) for runs in both]
    verdict = PASS if episodes[1] < episodes[0] and reached[1] else MISS
    measured = [_num(n, ",.0f") + ("" if done else " (not all reached)")
                for n, done in zip(episodes, reached, strict=True)]
    out.row("planning", f"real episodes to ≤ {planning.bound:g} on {planning.game}: "
            "Q-learning / Dyna-Q", " / ".join(measured), episodes, "Dyna-Q fewer", verdict)


def _programs_rows(out: _Judged, found: programs.ProgramsResult | None) -> None:
    if out.absent(found, "regret_separation_ratio", "protocol_steps_per_second",
                  "mcp_steps_per_second"):
        return
    sep = found.separation
    out.row("episodes_to_separate_by_return", "episodes to separate optimal from 5% "
            "deviations, by return", f"{_num(sep.by_return, ',.0f')}", sep.by_return)
    out.row("episodes_to_separate_by_regret", "  by exact regret",
            f"{_num(sep.by_regret, ',.0f')}", sep.by_regret)
    out.row("regret_separation_ratio", "  ratio", _num(sep.ratio, ".0f", "×"), sep.ratio,
            Target("≥", 10.0, "×"))
    rate = found.protocol.steps_per_second
    out.row("protocol_steps_per_second", f"protocol over a pipe, steps/s, {programs.WINDOW} "
            "requests in flight", _num(rate, ",.0f"), rate, Target("≥", 20_000.0, shown=",.0f"))
    trip = found.protocol_round_trip
    if trip.round_trips:
        out.row("protocol_round_trip_p50_us", "  one request at a time, round trip p50",
                f"{_num(trip.p50_us, '.0f', ' µs')} (p95 {_num(trip.p95_us, '.0f')}; "
                f"{_num(trip.rate.steps_per_second, ',.0f')} steps/s)", trip.p50_us)
    rate = found.mcp_together.steps_per_second
    if found.mcp_together.reason:
        out.missing("mcp_steps_per_second")
        out.rows.append(("MCP, steps/s", f"[dim]{found.mcp_together.reason}[/]", "", MISSING))
    else:
        out.row("mcp_steps_per_second", f"MCP, steps/s, {programs.MCP_GAMES} games at once",
                _num(rate, ",.0f"), rate, Target("≥", 1_000.0, shown=",.0f"))
        one = found.mcp_one.steps_per_second
        out.row("mcp_steps_per_second_one_call_at_a_time", "  one call at a time",
                _num(one, ",.0f"), one)


def _seeds_rows(out: _Judged, results: BenchResults) -> None:
    found = results.seeds
    if out.absent(found, "compare_speedup", "example_6_6"):
        return
    learners = found.seeds * len(found.algorithms)
    speedup = ratio(found.tutorial_s, found.compare_s)
    scaled = ("" if found.tutorial_learners == learners else
              f", {found.tutorial_learners} of {learners} run, scaled")
    out.row("compare_speedup", f"compare on {found.game}, {found.seeds} seeds × "
            f"{found.episodes} ep: tutorial loop ÷ compare", f"{_num(speedup, '.1f', '×')} "
            f"({found.tutorial_s:.1f} s{scaled} / {found.compare_s:.2f} s)", speedup,
            Target("≥", 100.0, "×"))
    online = found.online_returns
    if len(online) != 2:
        out.missing("example_6_6")
        return
    out.row("example_6_6", "  Example 6.6: mean online return, Q-learning / SARSA",
            f"{online[0]:+.1f} / {online[1]:+.1f}", list(online), "SARSA above",
            MISSING if math.isnan(online[1]) else PASS if online[1] > online[0] else MISS)


def _history_rows(out: _Judged, found: history.HistoryResult | None) -> None:
    if out.absent(found, "history_overhead", "history_mb_per_1000_runs"):
        return
    out.row("history_overhead", f"run history: recording's share of a train {found.game} run",
            f"{median(found.shares):.2%} (median of {len(found.shares)})", median(found.shares),
            Target("≤", 0.02, shown=".0%"))
    fastest = min(found.recorded_s), min(found.unrecorded_s)
    out.row("history_ab_ratio", "  whole run, fastest recorded ÷ fastest --no-record (noisy)",
            f"{fastest[0] / fastest[1]:.3f} ({fastest[0]:.2f} s / {fastest[1]:.2f} s)",
            fastest[0] / fastest[1])
    size = found.size_bytes / found.runs / 1000  # MB per 1,000 runs
    out.row("history_mb_per_1000_runs", f"run history: file size per 1,000 default runs "
            f"({found.runs:,} written)", f"{size:.3f} MB", size, Target("<", 1.0, " MB"))


def _tasks_rows(out: _Judged, found: compare.TasksResult | None) -> None:
    if out.absent(found, "task_split_overhead", "cluster_throughput_share"):
        return
    split, share = ratio(found.tasks_s, found.batch_s), ratio(found.local_s, found.cluster_s)
    out.row("task_split_overhead", f"compare on {found.game}, {found.seeds} seeds: "
            f"{found.tasks} tasks, recorded ÷ one batch", "n/a" if split is None else
            f"{split:.3f} ({found.tasks_s:.2f} s / {found.batch_s:.2f} s)", split,
            Target("≤", 1.10))
    target = Target("≥", 0.8)  # the cluster's throughput ÷ the local executor's
    workers = f"LocalCluster({compare.CLUSTER_WORKERS}) ÷ local executor, throughput"
    if share is None:
        out.row("cluster_throughput_share", workers, found.cluster_note or "n/a", None, target)
    else:
        out.row("cluster_throughput_share", f"{workers}, sweep of {len(compare.SWEEP_RATES)} "
                f"points", f"{share:.3f} ({found.local_s:.2f} s / {found.cluster_s:.2f} s)",
                share, target)


def _dp_rows(out: _Judged, found: dp.DPResult | None) -> None:
    if out.absent(found, "taxi_sweep_ms", "jack_policy_iteration_s", "plan_view"):
        return
    out.row("taxi_sweep_ms", "planning: a value-iteration sweep on Taxi (500 × 6), median",
            f"{found.taxi_sweep_ms:.2f} ms", found.taxi_sweep_ms, Target("≤", 5.0, " ms"))
    out.row("jack_policy_iteration_s", "  Jack's car rental by policy iteration (Figure 4.2), "
            "median", f"{found.jack_seconds:.2f} s (model built once: "
            f"{found.jack_model_seconds:.2f} s)", found.jack_seconds, Target("≤", 1.0, " s"))
    for view in found.views:
        out.row(f"plan_sweeps_per_second[{view.game}]", f"  Plan view on {view.game}: sweeps "
                "drawn a second (50/s asked)", f"{view.sweeps_per_second:.1f}",
                view.sweeps_per_second, Target("≥", 20.0))
        p95 = percentile(view.keys_ms, 95)
        out.row(f"plan_key_p95_ms[{view.game}]", f"  Plan view on {view.game}: key → screen "
                f"p95 while it runs", f"{p95:.0f} ms (p50 {median(view.keys_ms):.0f}, "
                f"n={len(view.keys_ms)})", p95, Target("≤", 50.0, " ms"))


def verdicts(results: BenchResults) -> dict[str, str]:
    """Each target's verdict, keyed like the JSON's figures."""
    return _judged(results).verdicts


def to_json(results: BenchResults) -> dict[str, Any]:
    """The JSON object `tui-gym bench --json` prints: every stage's measurements, each
    figure of the table by its key, and the targets' verdicts (NaN and missing: null)."""
    judged = _judged(results)
    return {**asdict(results), "figures": judged.values, "verdicts": judged.verdicts}


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
    if results.parts:
        lines.append("Textual's own X: the app with that part of ui/textual_internals.py left to "
                     "Textual (TUI_GYM_STOCK_TEXTUAL=X), measured like the figures with every "
                     "part in use; a part whose figures are no better than Textual's buys nothing.")
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
