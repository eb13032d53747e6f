"""The bench's output: one table (each figure, its target, PASS or MISS) or one JSON object."""

from __future__ import annotations

import math
from typing import Any

from rich.table import Table

from tui_gym.bench import dp, history, programs, tasks
from tui_gym.bench.live import RUNNERS
from tui_gym.bench.results import BenchResults

SPEED_TARGET = 100.0
GAP_SPEEDUP_TARGET = 50.0
COLD_COMPILE_S_TARGET = 30.0
WARM_LOAD_S_TARGET = 1.0
DEFAULTS_SHARE_TARGET = 0.95
LIVE_RATIO_TARGET = 0.8
REFRESH_HZ_TARGET = 10.0
KEY_P95_MS_TARGET = 50.0
RSS_GROWTH_MB_TARGET = 20.0
RSS_EPISODES_TARGET = 2_000_000
STARTUP_S_TARGET = 1.0
SEPARATION_RATIO_TARGET = 10.0
PROTOCOL_STEPS_TARGET = 20_000.0
MCP_STEPS_TARGET = 1_000.0
COMPARE_SPEEDUP_TARGET = 100.0
MAP_EDIT_MS_TARGET = 50.0

PASS, MISS, UNDECIDED, MISSING, LESSON = "PASS", "MISS", "?", "n/a", "lesson"


def _ok(value: float | None, good: bool) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return MISSING
    return PASS if good else MISS


def verdicts(results: BenchResults) -> dict[str, str]:
    """Each target's verdict, keyed like the JSON's figures."""
    out: dict[str, str] = {}
    found_compile = results.compile
    cold = found_compile.cold_s if found_compile else None
    warm = found_compile.warm_s if found_compile else None
    out["cold_compile_s"] = _ok(cold, (cold or 0) <= COLD_COMPILE_S_TARGET)
    out["warm_load_s"] = _ok(warm, (warm or 0) <= WARM_LOAD_S_TARGET)
    for speed in results.speed or ():
        up = speed.speedup
        out[f"speedup[{speed.game}/{speed.algorithm}]"] = _ok(up, (up or 0) >= SPEED_TARGET)
    if "speed" in results.errors:
        out["speedup"] = MISSING
    for found_defaults in results.defaults or ():
        out[f"defaults[{found_defaults.game}/{found_defaults.algorithm}]"] = (
            LESSON if found_defaults.lesson else
            _ok(found_defaults.share, found_defaults.share >= DEFAULTS_SHARE_TARGET))
    if "defaults" in results.errors:
        out["defaults"] = MISSING
    for name, gap in results.gap.items():
        key = f"time_to_gap[{name}]"
        if gap.speedup is None:
            out[key] = MISSING
        elif not gap.reached:
            out[key] = MISS
        elif gap.speedup >= GAP_SPEEDUP_TARGET:
            out[key] = PASS  # a lower bound above the target decides it too
        else:
            out[key] = MISS if gap.tutorial_reached else UNDECIDED
    for runner in RUNNERS:
        live = results.live_for(runner)
        if live is None:
            for name in ("live_ratio", "ui_refresh_hz", "key_latency_p95_ms"):
                out[f"{name}[{runner}]"] = MISSING
            continue
        out[f"live_ratio[{runner}]"] = _ok(live.live_ratio, live.live_ratio >= LIVE_RATIO_TARGET)
        out[f"ui_refresh_hz[{runner}]"] = _ok(live.refresh_hz, live.refresh_hz >= REFRESH_HZ_TARGET)
        p95 = live.key_latency_ms(95)
        out[f"key_latency_p95_ms[{runner}]"] = _ok(p95, p95 <= KEY_P95_MS_TARGET)
    memory = results.memory
    if memory is None:
        out["rss_growth_mb"] = MISSING
    else:
        good = memory.growth_mb < RSS_GROWTH_MB_TARGET and memory.episodes >= RSS_EPISODES_TARGET
        out["rss_growth_mb"] = _ok(memory.growth_mb, good)
    startup = results.startup
    seconds = startup.seconds if startup is not None else None
    out["startup_s"] = _ok(seconds, seconds is not None and seconds <= STARTUP_S_TARGET)
    for edit in results.map_edit or ():
        out[f"map_edit_ms[{edit.game}]"] = _ok(edit.median_ms, edit.median_ms <= MAP_EDIT_MS_TARGET)
    if "map_edit" in results.errors:
        out["map_edit_ms"] = MISSING
    planning = results.planning
    if planning is None:
        out["planning"] = MISSING
    else:
        fewer = planning.dyna_q_episodes < planning.q_learning_episodes
        out["planning"] = PASS if fewer and all(r.reached for r in planning.dyna_q) else MISS
    found = results.programs
    ratio = found.separation.ratio if found else None
    out["regret_separation_ratio"] = _ok(ratio, ratio is not None and
                                         ratio >= SEPARATION_RATIO_TARGET)
    rate = found.protocol.steps_per_second if found else None
    out["protocol_steps_per_second"] = _ok(rate, rate is not None and rate >= PROTOCOL_STEPS_TARGET)
    rate = found.mcp_together.steps_per_second if found else None
    out["mcp_steps_per_second"] = _ok(rate, rate is not None and rate >= MCP_STEPS_TARGET)
    found_seeds = results.seeds
    up = found_seeds.speedup if found_seeds else None
    out["compare_speedup"] = _ok(up, up is not None and up >= COMPARE_SPEEDUP_TARGET)
    online = found_seeds.online_returns if found_seeds else ()
    out["example_6_6"] = _ok(online[1] if len(online) == 2 else None,
                             len(online) == 2 and online[1] > online[0])
    out.update(history.verdicts(results.history, MISSING, _ok))
    out.update(tasks.verdicts(results.tasks, MISSING, _ok))
    out.update(dp.verdicts(results.dp, MISSING, _ok))
    return out


def _seeds_dict(results: BenchResults) -> dict[str, Any] | None:
    found = results.seeds
    if found is None:
        return None
    return {
        "game": found.game, "algorithms": list(found.algorithms), "seeds": found.seeds,
        "episodes": found.episodes, "compare_s": found.compare_s, "tutorial_s": found.tutorial_s,
        "tutorial_learners_run": found.tutorial_learners, "speedup": found.speedup,
        "online_return": dict(zip(found.algorithms, found.online_returns, strict=False)),
    }


def _programs_dict(results: BenchResults) -> dict[str, Any] | None:
    found = results.programs
    if found is None:
        return None
    sep = found.separation
    trip = found.protocol_round_trip
    return {
        "separation": {
            "episodes_each": sep.episodes, "deviation": programs.DEVIATION, "delta": sep.delta,
            "return_gap_measured": sep.return_gap, "return_sd": list(sep.return_sd),
            "regret_sd": list(sep.regret_sd), "episodes_needed_by_return": sep.by_return,
            "episodes_needed_by_regret": sep.by_regret, "ratio": sep.ratio,
            "formula": "n = 1.96^2 (sd_a^2 + sd_b^2) / delta^2",
        },
        "protocol_steps_per_second": found.protocol.steps_per_second,
        "protocol_samples": list(found.protocol.samples),
        "protocol_requests_in_flight": programs.WINDOW,
        "protocol_steps_per_second_one_request_at_a_time": trip.rate.steps_per_second,
        "protocol_round_trip_p50_us": trip.p50_us,
        "protocol_round_trip_p95_us": trip.p95_us,
        "protocol_round_trips": trip.round_trips,
        "mcp_steps_per_second_one_call_at_a_time": found.mcp_one.steps_per_second,
        "mcp_steps_per_second": found.mcp_together.steps_per_second,
        "mcp_games_at_once": programs.MCP_GAMES,
        "mcp_note": found.mcp_together.reason,
    }


# --- JSON --------------------------------------------------------------------
def _runner_dict(results: BenchResults, runner: str) -> dict[str, Any]:
    live = results.live.get(runner)
    if live is None or not live.repeats:
        return {"error": "; ".join(live.errors) if live is not None else "not measured"}
    return {
        "engine": live.engine, "live_ratio": live.live_ratio,
        "headless_episodes_per_second": live.headless_eps,
        "live_episodes_per_second": live.live_eps, "ui_refresh_hz": live.refresh_hz,
        "frames_hz": live.frames_hz, "key_latency_p50_ms": live.key_latency_ms(50),
        "key_latency_p95_ms": live.key_latency_ms(95), "key_presses": live.presses,
        "key_latency_by_key_ms": live.breakdown_ms(), "repeats": len(live.repeats),
        "window_s": live.seconds, "ratios": [r.ratio for r in live.repeats],
    }


def _game_dict(results: BenchResults, name: str) -> dict[str, Any]:
    gap = results.gap.get(name)
    return {
        "title": gap.title if gap is not None else name,
        "target_gap": gap.target if gap else None,
        "time_to_gap_s": gap.time_to_gap_s if gap else None,
        "time_to_gap_reached": gap.reached if gap else None,
        "time_to_gap_episodes": [r.episodes for r in gap.ours] if gap else None,
        "tutorial_time_to_gap_s": gap.tutorial_time_to_gap_s if gap else None,
        "tutorial_reached": gap.tutorial_reached if gap else None,
        "tutorial_time_to_gap_episodes": [r.episodes for r in gap.tutorial] if gap else None,
        "time_to_gap_speedup": gap.speedup if gap else None,
        "time_to_gap_speedup_is_lower_bound": (not gap.tutorial_reached) if gap else None,
        "speed": [
            {"algorithm": s.algorithm, "episodes_per_second": s.episodes,
             "tutorial_episodes_per_second": s.tutorial_episodes, "speedup": s.speedup,
             "steps_per_second": s.steps, "tutorial_steps_per_second": s.tutorial_steps}
            for s in results.speed or () if s.game == name
        ],
        "defaults": [
            {"algorithm": d.algorithm, "bound": d.bound, "met": d.met, "seeds": d.seeds,
             "share": d.share, "worst": d.worst, "lesson": d.lesson or None}
            for d in results.defaults or () if d.game == name
        ],
    }


def _planning_dict(results: BenchResults) -> dict[str, Any] | None:
    planning = results.planning
    if planning is None:
        return None
    return {
        "game": planning.game,
        "measure": planning.measure,
        "bound": planning.bound,
        "q_learning_episodes": planning.q_learning_episodes,
        "dyna_q_episodes": planning.dyna_q_episodes,
        "q_learning_runs": [{"seed": r.seed, "episodes": r.episodes, "reached": r.reached}
                            for r in planning.q_learning],
        "dyna_q_runs": [{"seed": r.seed, "episodes": r.episodes, "reached": r.reached}
                        for r in planning.dyna_q],
    }


def to_json(results: BenchResults) -> dict[str, Any]:
    """The JSON object `tui-gym bench --json` prints (NaN and missing figures are null).

    `games` holds every game's figures; the top-level throughput and gap figures are
    those of the first game measured."""
    names = list(dict.fromkeys([*(x.game for x in results.speed or ()), *results.gap,
                                *(d.game for d in results.defaults or ())]))
    memory, startup, found_compile = results.memory, results.startup, results.compile
    default = results.live_for(results.default_runner)
    machine = results.machine
    data: dict[str, Any] = {
        "quick": results.quick,
        "seconds": results.seconds,
        "machine": {
            "cpus": machine.cpus,
            "load_average_before": list(machine.load_before) if machine.load_before else None,
            "load_average_after": list(machine.load_after) if machine.load_after else None,
        },
        "cold_compile_s": found_compile.cold_s if found_compile else None,
        "numba_import_s": found_compile.import_s if found_compile else None,
        "warm_load_s": found_compile.warm_s if found_compile else None,
        **{key: value for key, value in _game_dict(results, next(iter(results.gap), "")).items()
           if key not in ("title", "speed", "defaults")},
        "games": {name: _game_dict(results, name) for name in names},
        "default_runner": results.default_runner,
        "live_ratio": default.live_ratio if default else None,
        "ui_refresh_hz": default.refresh_hz if default else None,
        "key_latency_p50_ms": default.key_latency_ms(50) if default else None,
        "key_latency_p95_ms": default.key_latency_ms(95) if default else None,
        "runners": {runner: _runner_dict(results, runner) for runner in RUNNERS},
        "rss_growth_mb": memory.growth_mb if memory else None,
        "rss": (
            {
                "episodes": memory.episodes, "warmup_episodes": memory.warmup,
                "engine": memory.engine, "start_mb": memory.rss_start_mb,
                "end_mb": memory.rss_end_mb, "peak_mb": memory.rss_peak_mb,
            }
            if memory
            else None
        ),
        "startup_s": startup.seconds if startup else None,
        "startup_samples_s": list(startup.samples) if startup else None,
        "planning": _planning_dict(results),
        "programs": _programs_dict(results),
        "map_edit": [
            {"game": e.game, "size": e.size, "edits": e.edits, "median_ms": e.median_ms,
             "worst_ms": e.worst_ms, "kept_agent": e.kept_agent}
            for e in results.map_edit or ()
        ],
        "history": history.to_json(results.history),
        "tasks": tasks.to_json(results.tasks),
        "compare": _seeds_dict(results),
        "planning_dp": dp.to_json(results.dp),
        "verdicts": verdicts(results),
        "errors": dict(results.errors),
    }
    return data


# --- the table -----------------------------------------------------------------
def _num(value: float | None, fmt: str, suffix: str = "") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return f"{value:{fmt}}{suffix}"


_STYLE = {PASS: "[bold green]PASS[/]", MISS: "[bold red]MISS[/]", UNDECIDED: "[yellow]?[/]",
          MISSING: "[dim]n/a[/]", LESSON: "[dim]lesson[/]"}


def table(results: BenchResults) -> Table:
    """Every figure beside its target and verdict."""
    verdict = verdicts(results)
    mode = "quick" if results.quick else "full"
    machine = results.machine
    load = ""
    if machine.load_before and machine.load_after:
        load = (f"; load average {machine.load_before[0]:.2f} before, "
                f"{machine.load_after[0]:.2f} after")
    out = Table(
        title=f"tui-gym bench ({mode}, {results.seconds:.0f} s, "
        f"{machine.cpus or '?'} CPUs{load})",
        title_justify="left",
    )
    out.add_column("figure", style="bold")
    out.add_column("measured", justify="right")
    out.add_column("target", justify="right")
    out.add_column("", justify="center")

    def row(label: str, value: str, target: str = "", key: str | None = None) -> None:
        out.add_row(label, value, target, _STYLE[verdict[key]] if key else "")

    found_compile = results.compile
    if found_compile is not None:
        row("every learner compiled, empty cache", f"{found_compile.cold_s:.1f} s",
            f"≤ {COLD_COMPILE_S_TARGET:g} s", "cold_compile_s")
        row("  loaded from the cache", f"{found_compile.warm_s:.2f} s (importing Numba "
            f"{found_compile.import_s:.2f} s)", f"≤ {WARM_LOAD_S_TARGET:g} s", "warm_load_s")
    for speed in results.speed or ():
        row(f"{speed.game}, {speed.algorithm}: ours ÷ tutorial loop",
            f"{_num(speed.speedup, ',.0f', '×')} ({_num(speed.episodes, ',.0f')} / "
            f"{_num(speed.tutorial_episodes, ',.0f')} ep/s)", f"≥ {SPEED_TARGET:g}×",
            f"speedup[{speed.game}/{speed.algorithm}]")
    for name, gap in results.gap.items():
        ours_eps = sorted(r.episodes for r in gap.ours)
        mark = "" if gap.reached else " (not reached)"
        row(f"{gap.title}: time to gap ≤ {gap.target:.4g}, ours",
            f"{_num(gap.time_to_gap_s, '.2f', ' s')}{mark}, "
            f"{ours_eps[len(ours_eps) // 2]:,} ep")
        theirs_eps = sorted(r.episodes for r in gap.tutorial)
        prefix = "" if gap.tutorial_reached else "≥ "
        mark = "" if gap.tutorial_reached else " (capped)"
        row("  tutorial loop",
            f"{prefix}{_num(gap.tutorial_time_to_gap_s, '.1f', ' s')}{mark}, "
            f"{theirs_eps[len(theirs_eps) // 2]:,} ep" if theirs_eps else "n/a")
        row("  tutorial time / ours", prefix + _num(gap.speedup, ".0f", "×"),
            f"≥ {GAP_SPEEDUP_TARGET:g}×", f"time_to_gap[{name}]")
    for runner in RUNNERS:
        name = f"{runner} runner" + (" (default)" if runner == results.default_runner else "")
        live = results.live_for(runner)
        if live is None:
            failed = results.live.get(runner)
            text = "; ".join(failed.errors) if failed is not None else "not measured"
            out.add_row(f"live, {name}", f"[red]{text}[/]", "", _STYLE[MISSING])
            continue
        row(f"live ep/s ÷ headless, {name}",
            f"{live.live_ratio:.2f} ({live.live_eps:,.0f} / {live.headless_eps:,.0f})",
            f"≥ {LIVE_RATIO_TARGET:.2f}", f"live_ratio[{runner}]")
        row(f"  snapshots drawn, {runner}", f"{live.refresh_hz:.1f} Hz",
            f"≥ {REFRESH_HZ_TARGET:g} Hz", f"ui_refresh_hz[{runner}]")
        row(f"  key → screen p95, {runner}",
            f"{live.key_latency_ms(95):.0f} ms (p50 {live.key_latency_ms(50):.0f}, "
            f"n={live.presses})",
            f"≤ {KEY_P95_MS_TARGET:g} ms", f"key_latency_p95_ms[{runner}]")
    memory = results.memory
    if memory is not None:
        row(f"RSS growth over {memory.episodes:,} ep ({memory.engine})",
            f"{memory.growth_mb:+.1f} MB", f"< {RSS_GROWTH_MB_TARGET:g} MB", "rss_growth_mb")
    if results.startup is not None:
        samples = ", ".join(f"{s:.2f}" for s in results.startup.samples)
        row("start to first frame", f"{results.startup.seconds:.2f} s ({samples})",
            f"≤ {STARTUP_S_TARGET:g} s", "startup_s")
    for edit in results.map_edit or ():
        row(f"{edit.game}: map edit → new optimum, {edit.size} (median, worst of {edit.edits})",
            f"{edit.median_ms:.0f} ms (worst {edit.worst_ms:.0f})",
            f"≤ {MAP_EDIT_MS_TARGET:g} ms", f"map_edit_ms[{edit.game}]")
    planning = results.planning
    if planning is not None:
        def runs(items: tuple) -> str:
            return _num(median_of(items), ",.0f") + ("" if all(r.reached for r in items)
                                                       else " (not all reached)")
        row(f"real episodes to ≤ {planning.bound:g} on {planning.game}: Q-learning / Dyna-Q",
            f"{runs(planning.q_learning)} / {runs(planning.dyna_q)}",
            "Dyna-Q fewer", "planning")
    found = results.programs
    if found is not None:
        sep = found.separation
        row("episodes to separate optimal from 5% deviations, by return",
            f"{_num(sep.by_return, ',.0f')}")
        row("  by exact regret", f"{_num(sep.by_regret, ',.0f')}")
        row("  ratio", _num(sep.ratio, ".0f", "×"), f"≥ {SEPARATION_RATIO_TARGET:g}×",
            "regret_separation_ratio")
        row(f"protocol over a pipe, steps/s, {programs.WINDOW} requests in flight",
            _num(found.protocol.steps_per_second, ",.0f"),
            f"≥ {PROTOCOL_STEPS_TARGET:,.0f}", "protocol_steps_per_second")
        trip = found.protocol_round_trip
        if trip.round_trips:
            row("  one request at a time, round trip p50",
                f"{_num(trip.p50_us, '.0f', ' µs')} (p95 {_num(trip.p95_us, '.0f')}; "
                f"{_num(trip.rate.steps_per_second, ',.0f')} steps/s)")
        if found.mcp_together.reason:
            out.add_row("MCP, steps/s", f"[dim]{found.mcp_together.reason}[/]", "", _STYLE[MISSING])
        else:
            row(f"MCP, steps/s, {programs.MCP_GAMES} games at once",
                _num(found.mcp_together.steps_per_second, ",.0f"),
                f"≥ {MCP_STEPS_TARGET:,.0f}", "mcp_steps_per_second")
            row("  one call at a time", _num(found.mcp_one.steps_per_second, ",.0f"))
    found_seeds = results.seeds
    if found_seeds is not None:
        scaled = ("" if found_seeds.tutorial_learners == found_seeds.learners else
                  f", {found_seeds.tutorial_learners} of {found_seeds.learners} run, scaled")
        row(f"compare on {found_seeds.game}, {found_seeds.seeds} seeds × "
            f"{found_seeds.episodes} ep: tutorial loop ÷ compare",
            f"{_num(found_seeds.speedup, '.1f', '×')} ({found_seeds.tutorial_s:.1f} s{scaled} / "
            f"{found_seeds.compare_s:.2f} s)",
            f"≥ {COMPARE_SPEEDUP_TARGET:g}×", "compare_speedup")
        online = found_seeds.online_returns
        if len(online) == 2:
            row("  Example 6.6: mean online return, Q-learning / SARSA",
                f"{online[0]:+.1f} / {online[1]:+.1f}", "SARSA above", "example_6_6")
    for found_defaults in results.defaults or ():
        row(f"{found_defaults.game}, {found_defaults.algorithm}: defaults at the bound",
            f"{found_defaults.met} of {found_defaults.seeds} (worst {found_defaults.worst:.4g};"
            f" {found_defaults.bound})", f"≥ {DEFAULTS_SHARE_TARGET:.0%}",
            f"defaults[{found_defaults.game}/{found_defaults.algorithm}]")
    for label, value, target, verdict_key in (*history.rows(results.history),
                                              *tasks.rows(results.tasks),
                                              *dp.rows(results.dp)):
        row(label, value, target, verdict_key)
    for stage, error in results.errors.items():
        out.add_row(f"{stage} failed", f"[red]{error}[/]", "", _STYLE[MISSING])
    return out


def median_of(runs: tuple) -> float:
    """The median episode count of planning runs."""
    from tui_gym.bench.figures import median

    return median([r.episodes for r in runs])


def notes(results: BenchResults) -> list[str]:
    """Lines to print under the table: what the figures are, and any lower bounds."""
    lines = [
        "Ratios are taken between figures measured in this run; speeds are medians over "
        "repeats, key latency percentiles over all presses.",
    ]
    verdict = verdicts(results)
    others = [r for r in RUNNERS if r != results.default_runner]
    if verdict.get(f"live_ratio[{results.default_runner}]") == PASS and any(
        verdict.get(f"live_ratio[{r}]") == MISS for r in others
    ):
        lines.append(
            f"The app trains with the {results.default_runner} runner; the others are measured "
            "for comparison (a thread runner shares one interpreter lock with the UI, so the UI's "
            "drawing comes out of training time)."
        )
    if results.planning is not None:
        lines.append(
            f"Planning: the bound is on the {results.planning.measure}; episodes are real "
            "ones (Dyna-Q's simulated updates are not counted), medians over seeds."
        )
    capped = [gap.title for gap in results.gap.values() if not gap.tutorial_reached]
    if capped:
        lines.append(
            f"The tutorial loop was stopped by its time cap before reaching the gap on "
            f"{', '.join(capped)}: its time and the speed-up are lower bounds (run without "
            "--quick for longer caps)."
        )
    found = results.programs
    if found is not None:
        sep = found.separation
        lines.append(
            f"Episodes to separate: each player played {sep.episodes:,} Blackjack episodes on "
            "the same seeds; n = 1.96² (sd_a² + sd_b²) / Δ² episodes each, Δ the deviating "
            f"player's mean exact regret ({sep.delta:.4f}), sd the measured per-episode "
            f"standard deviations (return {sep.return_sd[1]:.3f}, regret "
            f"{sep.regret_sd[1]:.3f})."
        )
    load = results.machine.load_before
    cpus = results.machine.cpus or 1
    if load is not None and load[0] > 0.5 * cpus:
        lines.append(
            f"Load average {load[0]:.2f} on {cpus} CPUs when the run started (other work, or "
            "a run just before): absolute speeds may be low; ratios are less affected."
        )
    return lines
