"""`tui-gym book`: the figures listed, each one's claims borne out at the book's settings,
its JSON, and a claim that is not borne out said so in the verdict and the exit status."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tui_gym.cli import book_command, main
from tui_gym.session.book import figure_named, figures
from tui_gym.session.book.figure import (
    BookFigure,
    Chart,
    Check,
    FigureOptions,
    FigureResult,
    Series,
)

NAMES = [f.name for f in figures()]
EXACT = [f.name for f in figures() if f.runs is None]  # the run figures: test_book_runs.py


@pytest.mark.parametrize("name", EXACT)
def test_every_claim_of_the_exact_figure_is_borne_out(name: str) -> None:
    seen: list[tuple[int, int]] = []
    result = figure_named(name).run(FigureOptions(), lambda done, total, _: seen.append(
        (done, total)))
    assert result.checks and result.ok, [c for c in result.checks if not c.ok]
    assert result.series and seen and seen[-1][0] == seen[-1][1]


def test_the_figures_are_listed(capsys) -> None:
    assert main(["book"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in ("3.2", "3.5", "4.1", "4.2", "4.3"))
    assert main(["book", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert listed["schema"] == 1 and [f["figure"] for f in listed["figures"]] == NAMES


def test_a_figure_as_json(capsys) -> None:
    assert main(["book", "4.3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"schema", "figure", "title", "runs", "series", "checks"}
    assert data["figure"] == "4.3" and data["runs"] == 1
    final = [s for s in data["series"] if s["label"].endswith("(final)")][0]
    assert set(final) == {"label", "x", "y", "lo", "hi"} and len(final["x"]) == 99
    assert final["y"][49] == pytest.approx(0.4) and final["lo"] == final["y"]
    assert all(set(c) == {"claim", "book", "measured", "ok"} and c["ok"]
               for c in data["checks"])


def test_a_figure_drawn_in_the_terminal(capsys) -> None:
    assert main(["book", "figure 4.1"]) == 0
    out = capsys.readouterr().out
    assert "-14.0" in out and "✓ reproduced" in out and "fewer" in out


def test_a_claim_not_borne_out_says_so(monkeypatch, capsys) -> None:
    def run(options: FigureOptions, progress) -> FigureResult:
        series = Series("y", np.arange(3.0), np.zeros(3))
        return FigureResult("9.9", "a test figure", 1, (Chart("c", "x", (series,)),),
                            checks=(Check("zero is one", 1, 0, False),))

    fake = BookFigure("9.9", "a test figure", "", "gambler", run)
    monkeypatch.setattr(book_command, "figure_named", lambda name: fake)
    assert main(["book", "9.9"]) == 1
    assert "✗ differs" in capsys.readouterr().out
    assert main(["book", "9.9", "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["checks"][0]["ok"] is False


def test_an_unknown_figure_is_one_line(capsys) -> None:
    assert main(["book", "9.9"]) == 2
    err = capsys.readouterr().err
    assert "no book figure '9.9'" in err and "4.3" in err and err.count("\n") == 1
