"""Where a study's grid runs: in this process, on a local Dask cluster, or on an existing one.

``scheduler`` values accepted by :func:`open_backend` (and by
:func:`~mlsgalerkin.studies.engine.runner.run_study`):

``None`` or ``"local"``
    A :class:`distributed.LocalCluster` started for the study and closed after it: worker
    *processes* (one per core available to this process, or ``n_workers``), one thread each,
    with ``NUMBA_NUM_THREADS``, ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and
    ``MKL_NUM_THREADS`` set to 1, so that each measurement runs on one core and its wall time
    does not depend on the other workers' threads. The scheduler's HTTP server (dashboard)
    listens on a free port, so studies of several users on one machine do not collide.
``"serial"``
    Every point in this process, one after the other (no Dask). Handy for debugging a
    measurement and for tiny grids, where starting worker processes costs more than the work.
``"tcp://host:port"`` (or ``host:port``; any other string is refused before any work)
    The address of a running Dask scheduler (``dask scheduler`` plus ``dask worker ADDRESS``
    on the machines of a cluster): the grid fans out to its workers. The workers need
    ``mlsgalerkin`` installed; measurement functions travel to them with cloudpickle.
a :class:`distributed.Client`
    An open client, used as it is and left open.

Worker processes start with the ``spawn`` method, which re-imports the main script in each
worker: a script that starts a study must do so under ``if __name__ == "__main__":``.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

__all__ = [
    "LOCAL",
    "SERIAL",
    "SINGLE_THREAD_ENV",
    "Backend",
    "DaskBackend",
    "SchedulerError",
    "SerialBackend",
    "available_cores",
    "numeric_environment",
    "open_backend",
]

logger = logging.getLogger(__name__)

SERIAL = "serial"
LOCAL = "local"
#: Environment of local-cluster workers: one thread for every threaded library.
SINGLE_THREAD_ENV = {
    "NUMBA_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
}
#: Environment variables that change threads or the BLAS kernel (and with it the last bits of
#: BLAS results): recorded in the studies' provenance.
NUMERIC_ENV_VARS = (*SINGLE_THREAD_ENV, "OPENBLAS_CORETYPE", "NPY_DISABLE_CPU_FEATURES")
#: Seconds to wait for an existing scheduler to answer.
CONNECT_TIMEOUT_S = 20


class SchedulerError(ValueError):
    """A ``scheduler`` argument that cannot be used."""


class Backend(Protocol):
    """Runs tasks and yields their results as they complete."""

    description: str

    def run(self, task: Callable[..., Any], arguments: Sequence[tuple]) -> Iterator[Any]:
        """Yield ``task(*args)`` for every ``args`` of ``arguments``, in completion order."""
        ...  # pragma: no cover


class SerialBackend:
    """Runs every task in this process, in order."""

    description = "serial (this process)"

    def run(self, task: Callable[..., Any], arguments: Sequence[tuple]) -> Iterator[Any]:
        for args in arguments:
            yield task(*args)


class DaskBackend:
    """Submits every task to a Dask :class:`~distributed.Client`; yields results as they complete.

    On an error (or when the consumer stops early) the remaining tasks are cancelled.
    """

    def __init__(self, client: Any, description: str) -> None:
        self.client = client
        self.description = description

    @property
    def workers(self) -> list[str]:
        """Addresses of the cluster's workers."""
        return sorted(self.client.scheduler_info().get("workers", {}))

    def run(self, task: Callable[..., Any], arguments: Sequence[tuple]) -> Iterator[Any]:
        from distributed import as_completed

        futures = [self.client.submit(task, *args, pure=False) for args in arguments]
        try:
            for future in as_completed(futures):
                yield future.result()
        finally:
            pending = [f for f in futures if not f.done()]
            if pending:
                self.client.cancel(pending)


def numeric_environment() -> dict[str, str]:
    """The :data:`NUMERIC_ENV_VARS` set in this process (local-cluster workers inherit them, with
    the thread counts of :data:`SINGLE_THREAD_ENV`)."""
    return {k: os.environ[k] for k in NUMERIC_ENV_VARS if k in os.environ}


def available_cores() -> int:
    """Cores this process may run on (the CPU affinity where the OS reports it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # macOS, Windows
        return os.cpu_count() or 1


def _is_client(obj: Any) -> bool:
    try:
        from distributed import Client
    except ImportError:
        return False
    return isinstance(obj, Client)


def check_scheduler(scheduler: Any, n_workers: int | None) -> None:
    """Raise :class:`SchedulerError` for a ``scheduler``/``n_workers`` pair that cannot work."""
    if scheduler is not None and not isinstance(scheduler, str) and not _is_client(scheduler):
        raise SchedulerError(
            f"scheduler must be None, 'local', 'serial', a Dask scheduler address such as "
            f"'tcp://10.0.0.5:8786', or a distributed.Client; got {type(scheduler).__name__}"
        )
    if isinstance(scheduler, str) and not scheduler.strip():
        raise SchedulerError("scheduler is an empty string; use 'local', 'serial' or an address")
    if isinstance(scheduler, str) and scheduler not in (SERIAL, LOCAL):
        _check_address(scheduler)
    if n_workers is not None:
        if scheduler not in (None, LOCAL):
            raise SchedulerError(
                f"n_workers applies to the local cluster only (scheduler=None or 'local'), not "
                f"to scheduler={scheduler!r}; the size of an existing cluster is set where it runs"
            )
        if not isinstance(n_workers, int) or isinstance(n_workers, bool) or n_workers < 1:
            raise SchedulerError(f"n_workers must be an integer >= 1, got {n_workers!r}")


def _check_address(address: str) -> None:
    """:class:`SchedulerError` unless ``address`` reads as a Dask scheduler address
    (``tcp://host:port``, ``host:port``, ``tls://...``, ``inproc://...``)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme in ("tcp", "tls", "ws", "wss", "ucx"):
            parse_host_port(location)
    except ValueError as exc:
        raise SchedulerError(
            f"scheduler {address!r} is neither 'local', 'serial' nor a Dask scheduler address such as "
            f"'tcp://10.0.0.5:8786' ({exc})") from None


@contextmanager
def open_backend(scheduler: Any = None, n_workers: int | None = None) -> Iterator[Backend]:
    """The backend of ``scheduler`` (see the module docstring); closes what it opened."""
    check_scheduler(scheduler, n_workers)
    if scheduler == SERIAL:
        yield SerialBackend()
        return
    if _is_client(scheduler):
        yield DaskBackend(scheduler, f"Dask client of {scheduler.scheduler.address}")
        return
    from distributed import Client, LocalCluster

    if scheduler in (None, LOCAL):
        n = n_workers or available_cores()
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=":0", env=dict(SINGLE_THREAD_ENV))
        try:
            with Client(cluster) as client:
                logger.info("local Dask cluster with %d workers started (dashboard %s)", n,
                            client.dashboard_link)
                yield DaskBackend(client, f"local Dask cluster ({n} worker processes, 1 thread "
                                          "each)")
        finally:
            cluster.close()
        return
    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SchedulerError(
            f"cannot reach a Dask scheduler at {scheduler!r} within {CONNECT_TIMEOUT_S} s "
            f"({exc}); start one with `dask scheduler` and workers with `dask worker "
            f"{scheduler}`, or use scheduler='local' for a cluster on this machine"
        ) from exc
    try:
        logger.info("connected to the Dask scheduler at %s", scheduler)
        yield DaskBackend(client, f"Dask cluster at {scheduler}")
    finally:
        client.close()
