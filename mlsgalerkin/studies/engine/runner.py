"""Run a measurement at every point of a grid and collect error *and* wall-time records.

:func:`run_study` checks everything it can before any work starts (the grid fits the
measurement's signature, the timing policy, the scheduler, that the functions can travel to Dask
workers), then runs one task per grid point on the chosen backend
(:mod:`~mlsgalerkin.studies.engine.schedulers`) with a tqdm bar over completed points.

One task:

1. the first task of a warm-up (``warm_up``, e.g. compiling numba kernels) runs it once in that
   worker process, untimed;
2. numba is limited to ``numba_threads`` threads for the task;
3. ``measure(**point)`` is called and timed by :func:`~mlsgalerkin.studies.engine.timing.best_time`;
4. its return value, a mapping of measures (or a list of mappings, one record each, e.g. one
   per evaluation region), becomes the record(s): the point's parameters, the measures, then
   ``wall_time_s`` (best seconds per call of ``measure``) and ``worker`` (the Dask worker address,
   or ``serial@HOST:PID``).

A measure may repeat a parameter's name only with the parameter's own value. Records are sorted
by grid index (and, within a point, in the measure's order), so every scheduler gives the same
records in the same order; only the timing columns differ. An exception in a measurement stops
the study with a :class:`MeasurementError` naming the point, its parameters, the worker and the
original traceback.

>>> result = run_study({"n": [10, 100]}, lambda n: {"total": sum(range(n))}, scheduler="serial",
...                    progress=False)
>>> [(r["n"], r["total"]) for r in result.records]
[(10, 45), (100, 4950)]
>>> sorted(result.records[0])
['n', 'total', 'wall_time_s', 'worker']
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import socket
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.engine.grid import RESERVED_COLUMNS, Grid, as_grid
from mlsgalerkin.studies.engine.result import StudyResult
from mlsgalerkin.studies.engine.rowlog import RowLog
from mlsgalerkin.studies.engine.schedulers import SERIAL, check_scheduler, open_backend
from mlsgalerkin.studies.engine.timing import TimingPolicy, best_time

__all__ = ["MeasurementError", "PointOutcome", "measure_point", "run_study", "worker_name"]

logger = logging.getLogger(__name__)

#: Warm-ups already run in this process (keyed by the study's warm-up token).
_WARMED_UP: set[str] = set()
_WARM_UP_LOCK = threading.Lock()


class MeasurementError(RuntimeError):
    """A measurement failed, or returned something that is not a record, at one grid point."""

    def __init__(self, message: str, index: int | None = None,
                 params: dict[str, Any] | None = None) -> None:
        super().__init__(message, index, params)
        self.message = message
        self.index = index
        self.params = params

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class PointOutcome:
    """What one task sends back: the measures of point ``index``, its time and its worker."""

    index: int
    measures: tuple[dict[str, Any], ...]
    wall_time_s: float
    worker: str


def worker_name() -> str:
    """The Dask worker address of this task, or ``serial@HOST:PID`` outside a Dask worker."""
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return f"serial@{socket.gethostname()}:{os.getpid()}"


@contextmanager
def _numba_threads(n: int | None) -> Iterator[None]:
    if n is None:
        yield
        return
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(max(1, min(n, numba.config.NUMBA_NUM_THREADS)))
    try:
        yield
    finally:
        numba.set_num_threads(before)


def _same(a: Any, b: Any) -> bool:
    try:
        if a == b:
            return True
        return isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)
    except (TypeError, ValueError):  # e.g. arrays: an echo must be a plain value
        return False


def _as_measures(value: Any, index: int, params: dict[str, Any],
                 where: str) -> tuple[dict[str, Any], ...]:
    """The measurement's return value as a tuple of measure dicts (parameter echoes removed)."""
    items = [value] if isinstance(value, Mapping) else value
    if not isinstance(items, Sequence) or isinstance(items, (str, bytes)) or not all(
            isinstance(m, Mapping) for m in items):
        raise MeasurementError(
            f"the measurement at point #{index} {params} ({where}) returned a "
            f"{type(value).__name__}; return a dict of measures such as {{'error': 0.01}}, or a "
            "list of such dicts (one record each)", index, params)
    out = []
    for m in items:
        record = {}
        for key, v in m.items():
            if not isinstance(key, str) or key in RESERVED_COLUMNS:
                raise MeasurementError(
                    f"the measurement at point #{index} {params} ({where}) returned the key "
                    f"{key!r}: measure names must be strings other than {RESERVED_COLUMNS}, "
                    "which the engine adds itself", index, params)
            if key in params:
                if not _same(v, params[key]):
                    raise MeasurementError(
                        f"the measurement at point #{index} {params} ({where}) returned "
                        f"{key}={v!r}, but the parameter {key} is {params[key]!r}; a measure may "
                        "repeat a parameter only with its value: rename the measure", index,
                        params)
                continue
            record[key] = v
        out.append(record)
    return tuple(out)


def measure_point(measure: Callable[..., Any], index: int, params: dict[str, Any],
                  policy: TimingPolicy, warm_up: Callable[[], Any] | None, warm_up_key: str,
                  numba_threads: int | None) -> PointOutcome:
    """One task of :func:`run_study` (runs in a worker; see the module docstring)."""
    worker = worker_name()
    with _numba_threads(numba_threads):
        if warm_up is not None:
            with _WARM_UP_LOCK:
                if warm_up_key not in _WARMED_UP:
                    t0 = time.perf_counter()
                    warm_up()
                    _WARMED_UP.add(warm_up_key)
                    logger.info("warm-up on %s took %.1f s", worker,
                                time.perf_counter() - t0)
        try:
            value, seconds = best_time(lambda: measure(**params), policy.min_time,
                                       policy.repeats)
        except Exception as exc:
            tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
            raise MeasurementError(
                f"the measurement failed at grid point #{index} {params} on {worker}: "
                f"{type(exc).__name__}: {exc}\n--- traceback on the worker ---\n{tb}",
                index, params) from None
    return PointOutcome(index, _as_measures(value, index, params, worker), seconds, worker)


def _records(outcome: PointOutcome, point: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The records of one measured point: its parameters, each measure dict, time and worker."""
    return [{**point, **m, "wall_time_s": outcome.wall_time_s, "worker": outcome.worker}
            for m in outcome.measures]


def _log_point(log: RowLog, outcome: PointOutcome, point: Mapping[str, Any]) -> None:
    try:
        log.append(outcome.index, _records(outcome, point))
    except OSError as exc:
        raise OSError(exc.errno, f"writing the study's rows to {log.path} failed ({exc.strerror or exc}); the "
                                 f"{log.rows} rows measured before are in that file") from exc


def _warm_up_key(warm_up: Callable[[], Any] | None) -> str:
    """A token equal for equal warm-ups (the same function with the same arguments)."""
    if warm_up is None:
        return ""
    import hashlib

    import cloudpickle

    try:
        return hashlib.sha1(cloudpickle.dumps(warm_up)).hexdigest()
    except Exception:  # not picklable: only possible in serial runs, where identity suffices
        return f"id:{id(warm_up)}"


def _check_picklable(obj: Any, what: str) -> None:
    import cloudpickle

    try:
        cloudpickle.dumps(obj)
    except Exception as exc:
        raise TypeError(
            f"{what} cannot be sent to Dask workers ({type(exc).__name__}: {exc}); define it at "
            "module level without references to open files, locks or clients, or run with "
            "scheduler='serial'"
        ) from exc


def run_study(
    grid: Grid | Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]],
    measure: Callable[..., Mapping[str, Any] | Sequence[Mapping[str, Any]]],
    *,
    scheduler: Any = None,
    n_workers: int | None = None,
    repeats: int = 1,
    min_time: float = 0.0,
    warm_up: Callable[[], Any] | None = None,
    numba_threads: int | None = 1,
    progress: bool = True,
    description: str = "study",
    rows_log: str | Path | None = None,
) -> StudyResult:
    """Measure every point of ``grid`` with ``measure`` and return the records.

    Parameters
    ----------
    grid : :class:`~mlsgalerkin.studies.engine.grid.Grid`, a mapping of parameter names to
        value lists (their Cartesian product), or a sequence of points (dicts).
    measure : ``measure(**point) -> dict`` of measures (errors, sizes, ...), or a list of such
        dicts for several records per point. Must be deterministic; it is called at least once
        per point (more often under a ``repeats``/``min_time`` policy).
    scheduler : ``None``/``"local"`` (a local Dask cluster, the default), ``"serial"``, the
        address of a Dask scheduler, or a :class:`distributed.Client`; see
        :mod:`~mlsgalerkin.studies.engine.schedulers`.
    n_workers : worker processes of the local cluster (default: the available cores).
    repeats, min_time : timing policy of :func:`~mlsgalerkin.studies.engine.timing.best_time`.
    warm_up : called once per worker process before its first measurement, untimed (e.g.
        compile numba kernels on tiny inputs so that no wall time includes compilation).
    numba_threads : numba threads during a measurement (default 1: timings independent of the
        machine's load); ``None`` leaves numba alone.
    progress : show a tqdm bar over completed points.
    description : label of the progress bar and the log.
    rows_log : a file to which every point's records are appended as soon as it is measured
        (:class:`~mlsgalerkin.studies.engine.rowlog.RowLog`, JSON Lines): a study that stops
        early (a crash, a full disk) keeps every row measured so far there. Opened before any
        work, so an unwritable place is an immediate ``OSError``; a failed write stops the study
        with an ``OSError`` saying how many rows the file holds.

    Returns
    -------
    :class:`~mlsgalerkin.studies.engine.result.StudyResult` with one record per point (or per
    dict the measure returned), sorted by grid index.
    """
    grid = as_grid(grid)
    if not callable(measure):
        raise TypeError(f"measure must be callable as measure(**point), got {measure!r}")
    if warm_up is not None and not callable(warm_up):
        raise TypeError(f"warm_up must be a callable without arguments, got {warm_up!r}")
    grid.check_measure(measure)
    policy = TimingPolicy(repeats=repeats, min_time=min_time)
    if numba_threads is not None and (not isinstance(numba_threads, int)
                                      or isinstance(numba_threads, bool) or numba_threads < 1):
        raise ValueError(f"numba_threads must be an integer >= 1 or None, got {numba_threads!r}")
    check_scheduler(scheduler, n_workers)
    if scheduler != SERIAL:
        _check_picklable(measure, "the measurement")
        if warm_up is not None:
            _check_picklable(warm_up, "the warm-up")
    key = _warm_up_key(warm_up)
    arguments = [(measure, i, dict(point), policy, warm_up, key, numba_threads)
                 for i, point in enumerate(grid)]

    from tqdm.auto import tqdm

    points = list(grid)
    t0 = time.perf_counter()
    outcomes: dict[int, PointOutcome] = {}
    log = RowLog(rows_log) if rows_log is not None else contextlib.nullcontext()
    with log, open_backend(scheduler, n_workers) as backend:
        logger.info("%s: %d points on %s", description, len(grid), backend.description)
        with tqdm(total=len(grid), desc=description, unit="point", disable=not progress,
                  leave=False) as bar:
            for outcome in backend.run(measure_point, arguments):
                outcomes[outcome.index] = outcome
                if isinstance(log, RowLog):
                    _log_point(log, outcome, points[outcome.index])
                bar.update(1)
        scheduler_text = backend.description
    elapsed = time.perf_counter() - t0
    records = []
    for i, point in enumerate(points):
        records += _records(outcomes[i], point)
    logger.info("%s: %d records in %.1f s", description, len(records), elapsed)
    return StudyResult(records=records, parameters=grid.names, scheduler=scheduler_text,
                       timing=policy, wall_time_s=elapsed)
