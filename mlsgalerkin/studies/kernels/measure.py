"""Measuring one point of the kernel study: RMS errors, interior masks and the rows per region."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["interior_mask", "region_rows", "rms_error"]


def rms_error(
    approx: np.ndarray, exact: np.ndarray, mask: np.ndarray | None = None
) -> tuple[float, float]:
    """Absolute and relative RMS error (Xing 2019, eq. 12.67); relative = absolute / RMS(exact).

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


def interior_mask(x: np.ndarray, radius: float, lo: float = 0.0, hi: float = 1.0) -> np.ndarray:
    """Points whose ball of ``radius`` lies inside ``[lo, hi]^dim`` (1e-12 tolerance)."""
    x = np.asarray(x, float)
    if x.ndim == 1:
        x = x[:, None]
    tol = 1e-12
    return np.all((x - radius >= lo - tol) & (x + radius <= hi + tol), axis=1)


def region_rows(
    base: dict[str, Any],
    masks: dict[str, np.ndarray],
    approx: np.ndarray,
    exact: np.ndarray,
    *,
    wall_s: float,
    counts: np.ndarray | float | None = None,
    grad: np.ndarray | None = None,
    grad_exact: np.ndarray | None = None,
    cond: np.ndarray | None = None,
) -> list[dict[str, Any]]:
    """One row per non-empty region of ``masks``: ``base`` plus the RMS errors of ``approx``
    (and ``grad``) against the exact values, the largest gradient error and condition number,
    the mean neighbour count and ``wall_s`` (seconds)."""
    rows = []
    gerr = None if grad is None else np.linalg.norm(np.asarray(grad) - grad_exact, axis=1)
    for region, mask in masks.items():
        if not np.any(mask):
            continue
        ea, er = rms_error(approx, exact, mask)
        ga = gr = gm = cm = math.nan
        if grad is not None:
            ga, gr = rms_error(grad, grad_exact, mask)
            gm = float(gerr[mask].max())
        if cond is not None:
            cm = float(np.max(cond[mask]))
        nnb = float(np.mean(counts[mask])) if isinstance(counts, np.ndarray) else counts
        rows.append({
            **base,
            "region": region,
            "n_eval": int(np.count_nonzero(mask)),
            "error_abs": ea,
            "error_rel": er,
            "error_grad": ga,
            "error_grad_rel": gr,
            "error_grad_max": gm,
            "cond_max": cm,
            "n_neighbors": nnb,
            "wall_s": wall_s,
        })
    return rows
