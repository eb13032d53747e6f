"""Tasks on a Dask cluster: `connect(cluster)`, then `run_on_cluster(client, tasks, ...)`."""

from __future__ import annotations

import contextlib
import logging
import uuid
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TypeVar

__all__ = ["DASK_HINT", "ClusterError", "connect", "run_on_cluster"]

DASK_HINT = "--cluster needs Dask: pip install 'tui-gym[dask]'"
WAIT_SECONDS = 0.2  # how often the stop flag is looked at while tasks run
CONNECT_SECONDS = 10  # how long a scheduler's address is tried

T = TypeVar("T")
R = TypeVar("R")


class ClusterError(RuntimeError):
    """The cluster cannot be used (Dask missing, a scheduler out of reach, a bad address)."""


@contextlib.contextmanager
def connect(cluster: Any) -> Iterator[Any]:
    """A client of `cluster` while the block runs; ClusterError (one line) if there is none."""
    if not isinstance(cluster, str):
        yield cluster  # a Client the caller owns
        return
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError(DASK_HINT) from None
    if cluster.startswith("local:"):
        workers = cluster.removeprefix("local:")
        if not workers.isdigit() or not 1 <= int(workers) <= 256:
            raise ClusterError(f"--cluster {cluster}: expected local:N with N from 1 to 256")
        with LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                          dashboard_address=":0", silence_logs=logging.ERROR) as local, \
                Client(local) as client:
            yield client
        return
    try:
        client = Client(cluster, timeout=CONNECT_SECONDS)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ClusterError(f"cannot reach the Dask scheduler at {cluster}: {exc}") from None
    with client:
        yield client


def run_on_cluster(
    client: Any, tasks: Sequence[T], work: Callable[[T], R], take: Callable[[T, R], None],
    stopped: Callable[[], bool],
) -> bool:
    """Run `work(task)` for every task on the cluster, `take(task, result)` here as each lands;
    whether all landed (False: `stopped` first, the rest cancelled). A task's error raises here."""
    from distributed import wait

    run = uuid.uuid4().hex[:12]
    pending = {
        client.submit(work, task, key=f"tui-gym-{run}-{i}", pure=False): task
        for i, task in enumerate(tasks)
    }
    try:
        while pending:
            if stopped():
                return False
            try:
                done, _ = wait(list(pending), timeout=WAIT_SECONDS, return_when="FIRST_COMPLETED")
            except TimeoutError:
                continue
            for future in done:
                task = pending.pop(future)
                take(task, future.result())
        return True
    finally:
        if pending:
            client.cancel(list(pending))
