"""A recorded run as TensorBoard event files (`tui-gym runs export ID --tensorboard DIR`)."""

from __future__ import annotations

import json
import math
import re
import secrets
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tui_gym.core.experiments.errors import RunHistoryError
from tui_gym.core.experiments.figures import FieldsJson
from tui_gym.core.experiments.records import Curve
from tui_gym.core.experiments.runs import show_run

INSTALL_HINT = "pip install 'tui-gym[tensorboard]'"
EVENT_PREFIX = "events.out.tfevents."
_TAGS = {"return": "charts/episodic_return", "exact_value": "charts/exact_value"}


class TensorBoardUnavailable(RunHistoryError):
    """The optional TensorBoard writer (tensorboardX) is not installed."""


@dataclass(frozen=True)
class TensorBoardExport(FieldsJson):
    """Run `run` written as TensorBoard events: the file, its folder's parent, tags and values."""

    run: int
    path: Path
    logdir: Path
    tags: tuple[str, ...]
    scalars: int


def scalar_tag(curve_name: str) -> str:
    """The TensorBoard tag of a curve: `return` -> `charts/episodic_return`, `x.lo` -> `..._lo`."""
    base, dot, edge = curve_name.partition(".")
    tag = _TAGS.get(base, "charts/" + re.sub(r"[^A-Za-z0-9_\-]", "_", base))
    return f"{tag}_{edge}" if dot else tag


def _walltimes(curve: Curve, started: float, ended: float | None) -> list[float]:
    """When each point was reached, spread evenly by episode over the run's time."""
    if ended is None or len(curve) < 2:  # (its episodes strictly increase)
        return [started] * len(curve)
    return np.interp(curve.episodes, curve.episodes[[0, -1]], [started, ended]).tolist()


def export_run_tensorboard(
    run_id: int, directory: str | Path, db: str | None = None
) -> TensorBoardExport:
    """Write run `run_id`'s curves and figures as TensorBoard events under `directory`."""
    try:
        from tensorboardX import SummaryWriter
    except ImportError:
        raise TensorBoardUnavailable(
            f"TensorBoard export needs the tensorboard extra: {INSTALL_HINT}"
        ) from None
    record = show_run(run_id, db)
    summary = record.summary
    root = Path(directory).expanduser()
    words = re.sub(r"[^A-Za-z0-9_\-]+", "_", f"{summary.game}-{summary.algorithm}")
    folder = root / f"run-{summary.id}-{words}"
    tags: list[str] = []
    scalars = 0
    try:
        folder.mkdir(parents=True, exist_ok=True)
        earlier = set(folder.glob(EVENT_PREFIX + "*"))
        # A suffix of its own: an export within the same second gets a new file name too.
        suffix = f".{secrets.token_hex(4)}"
        writer = SummaryWriter(logdir=str(folder), flush_secs=3600, filename_suffix=suffix)
        try:
            for curve in record.curves:
                tag = scalar_tag(curve.name)
                tags.append(tag)
                times = _walltimes(curve, summary.started_at, summary.ended_at)
                for episode, value, when in zip(
                    curve.episodes.tolist(), curve.values.tolist(), times, strict=True
                ):
                    if math.isfinite(value):
                        writer.add_scalar(tag, value, global_step=episode, walltime=when)
                        scalars += 1
            end = summary.ended_at or summary.started_at
            last_episode = max((int(c.episodes[-1]) for c in record.curves if len(c)), default=0)
            for figure in summary.figures:
                if math.isfinite(figure.value):
                    tag = f"figures/{figure.name}"
                    tags.append(tag)
                    writer.add_scalar(tag, figure.value, global_step=last_episode, walltime=end)
                    scalars += 1
            settings = record.to_json(curves=False)
            settings.pop("figures", None)
            text = json.dumps(settings, indent=2, default=str)
            writer.add_text("run/settings", f"```\n{text}\n```", global_step=0,
                            walltime=summary.started_at)
        finally:
            writer.close()
        written = sorted(set(folder.glob(EVENT_PREFIX + "*")) - earlier)
        for old in earlier:
            old.unlink(missing_ok=True)
    except OSError as exc:
        raise RunHistoryError(f"cannot write {folder}: {exc.strerror or exc}") from None
    if not written:
        raise RunHistoryError(f"cannot write {folder}: no event file was written")
    return TensorBoardExport(run=summary.id, path=written[-1], logdir=root, tags=tuple(tags),
                             scalars=scalars)
