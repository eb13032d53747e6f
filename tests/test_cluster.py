"""`--cluster local:N`: a cluster of its own on this machine, whatever else holds Dask's
usual dashboard port."""

from __future__ import annotations

import contextlib
import socket
import warnings

import pytest

from tui_gym.session.experiments.cluster import connect


def test_a_local_cluster_starts_quietly_beside_another_on_the_dashboard_port() -> None:
    pytest.importorskip("distributed")
    with contextlib.ExitStack() as stack:
        other = stack.enter_context(socket.socket())
        with contextlib.suppress(OSError):  # taken already: the case this test is about
            other.bind(("", 8787))
            other.listen()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with connect("local:1") as client:
                assert client.submit(sum, [1, 2]).result() == 3
    assert not [str(w.message) for w in caught if "already in use" in str(w.message)]
