"""The compiled code's cache folder: one per version of the engine's and algorithms' sources,
shared by a process and the processes it starts."""

from __future__ import annotations

from pathlib import Path

from tui_gym.core.engine import jit


def test_a_child_process_uses_the_folder_its_parent_chose(tmp_path: Path) -> None:
    chosen = jit.cache_folder({"NUMBA_CACHE_DIR": str(tmp_path)})
    assert chosen.parent == tmp_path and chosen.name == f"numba-{jit.sources_hash()}"
    # start() hands the chosen folder on in NUMBA_CACHE_DIR: a child finds the same one.
    assert jit.cache_folder({"NUMBA_CACHE_DIR": str(chosen)}) == chosen
