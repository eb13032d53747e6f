"""Every file a user names is written by one checked writer: through symbolic links to the
file they point to, never over a pipe or a device, by an atomic rename; and a path that
cannot be written is said before any work is done."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from tui_gym.cli import main
from tui_gym.core.files import OutputPathError, check_output_path, write_atomically
from tui_gym.core.recording.writer import LineWriter

SHORT_TRAIN = ["--episodes", "300", "--eval-episodes", "10"]


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "pipe"
    os.mkfifo(path)
    return path


def _one_line(capsys: pytest.CaptureFixture[str], *fragments: str) -> None:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, err


def test_the_writer_follows_links_and_refuses_what_is_not_a_file(
    tmp_path: Path, fifo: Path
) -> None:
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert write_atomically(link, "new\n") == link
    assert link.is_symlink() and target.read_text() == "new\n"
    for path, why in ((fifo, "not a regular file"), (Path("/dev/null"), "not a regular file"),
                      (tmp_path, "is a folder"), (tmp_path / "no" / "x.csv", "does not exist")):
        with pytest.raises(OutputPathError, match=why):
            write_atomically(path, "x")
    assert stat.S_ISFIFO(fifo.stat().st_mode)  # still a pipe, not a file in its place
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "pipe", "real.csv"]


def test_a_recording_is_never_written_into_a_pipe_or_a_device(fifo: Path) -> None:
    for path in (fifo, Path("/dev/null")):
        with pytest.raises(OSError, match="not a regular file"):
            LineWriter(path)  # returns at once: opening the pipe does not wait for a reader
    assert stat.S_ISFIFO(fifo.stat().st_mode)


@pytest.mark.parametrize("flag", ["--csv", "--record"])
def test_compare_checks_its_output_paths_before_training(
    flag: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import tui_gym.session.experiments.compare as compare

    def trained(*args: object, **kwargs: object) -> None:
        raise AssertionError("training started")

    monkeypatch.setattr(compare, "run_compare", trained)
    if flag == "--record":  # compare has no --record: the app and `play` share the type
        command = ["play", "blackjack", "--jsonl", "--record", "/nonexistent/dir/x.jsonl"]
    else:
        command = ["compare", "blackjack", "--algorithms", "q-learning", "--csv",
                   "/nonexistent/dir/x.csv", "--no-record"]
    with pytest.raises(SystemExit) as exit_:
        main(command)
    assert exit_.value.code == 2
    _one_line(capsys, f"argument {flag}: /nonexistent/dir/x.", "the folder /nonexistent/dir "
              "does not exist")


def test_train_refuses_to_save_over_a_device_before_training(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        main(["train", "blackjack", *SHORT_TRAIN, "--save", "/dev/null", "--no-record"])
    _one_line(capsys, "argument --save: /dev/null: is not a regular file")


def test_compare_csv_through_a_link_writes_its_target(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "curves.csv"
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    code = main(["compare", "blackjack", "--algorithms", "q-learning", "--seeds", "2",
                 "--episodes", "200", "--processes", "0", "--no-record", "--csv", str(link),
                 "--json"])
    assert code == 0, capsys.readouterr().err
    assert link.is_symlink() and target.read_text().startswith("episode,q-learning.mean")


def test_runs_export_through_a_link_writes_its_target_and_refuses_a_pipe(
    tmp_path: Path, fifo: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = str(tmp_path / "runs.db")
    assert main(["train", "blackjack", *SHORT_TRAIN, "--db", db]) == 0
    target = tmp_path / "curves.csv"
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    capsys.readouterr()
    assert main(["runs", "export", "1", "--csv", str(link), "--db", db]) == 0
    assert link.is_symlink() and target.read_text().startswith("episode,")
    with pytest.raises(SystemExit):
        main(["runs", "export", "1", "--csv", str(fifo), "--db", db])
    _one_line(capsys, "is not a regular file")
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_a_map_is_saved_through_the_same_writer(tmp_path: Path, fifo: Path) -> None:
    from tui_gym.games.maps import MapError
    from tui_gym.games.maps.builtin import builtin_map
    from tui_gym.games.maps.files import read_map_file, write_map_file

    lake = builtin_map("4x4").grid_map
    with pytest.raises(MapError, match="not a regular file"):
        write_map_file(fifo, lake)
    link = tmp_path / "link.txt"
    link.symlink_to(tmp_path / "lake.txt")
    write_map_file(link, lake)
    assert link.is_symlink() and read_map_file(tmp_path / "lake.txt") == lake


def test_screenshots_check_every_file_before_drawing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import tui_gym.ui.screenshots as screenshots

    async def drawn(*args: object) -> Path:
        raise AssertionError("a screenshot was drawn")

    monkeypatch.setattr(screenshots, "_shoot", drawn)
    last = screenshots.SCENARIOS[-1].filename
    (tmp_path / last).mkdir()
    with pytest.raises(OutputPathError, match=f"{last}: is a folder"):
        screenshots.write_screenshots(tmp_path)
    assert check_output_path(tmp_path / "fine.svg") == tmp_path / "fine.svg"
