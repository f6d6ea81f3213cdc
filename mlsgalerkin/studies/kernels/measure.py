"""Measuring one point of the study: RMS errors, interior masks and wall times."""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

__all__ = ["interior_mask", "rms_error", "timed"]


def rms_error(
    approx: np.ndarray, exact: np.ndarray, mask: np.ndarray | None = None
) -> tuple[float, float]:
    """Absolute and relative RMS error (seed eq. 12.67); relative = absolute / RMS(exact).

    For vector data ``(n, dim)`` the pointwise error is the Euclidean norm.
    """
    a, e = np.asarray(approx, float), np.asarray(exact, float)
    if mask is not None:
        a, e = a[mask], e[mask]
    if e.size == 0:
        return math.nan, math.nan
    d2 = (a - e) ** 2
    s2 = e**2
    if d2.ndim == 2:
        d2, s2 = d2.sum(axis=1), s2.sum(axis=1)
    err = float(np.sqrt(np.mean(d2)))
    ref = float(np.sqrt(np.mean(s2)))
    return err, (err / ref if ref > 0 else math.nan)


def timed(fn: Callable[[], object], min_time: float, repeats: int = 1) -> tuple[object, float]:
    """Run ``fn`` and return ``(result, seconds per call)``.

    After the first call, ``repeats`` groups of calls, each lasting at least about ``min_time``,
    are timed; the result is the best per-call time seen (the minimum is the estimator least
    disturbed by other processes on a shared machine).
    """
    t0 = time.perf_counter()
    out = fn()
    best = time.perf_counter() - t0
    n = int(min(200, max(1, math.ceil(min_time / max(best, 1e-7)))))
    for _ in range(repeats if (repeats > 1 or best < min_time) else 0):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return out, best


def interior_mask(x: np.ndarray, radius: float, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Points whose ball of ``radius`` lies inside ``[lo, hi]^dim`` (1e-12 tolerance)."""
    x = np.asarray(x, float)
    if x.ndim == 1:
        x = x[:, None]
    tol = 1e-12
    return np.all((x - radius >= lo - tol) & (x + radius <= hi + tol), axis=1)
