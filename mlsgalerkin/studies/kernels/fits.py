"""Power-law fits of every measured series of the kernel study, and their lookup table."""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

from mlsgalerkin.analysis.convergence import fit_power_law
from mlsgalerkin.studies.kernels.config import FIT_COLUMNS

__all__ = ["compute_fits", "fit_lookup"]

_SWEEP_X = {
    "h": "h",
    "n_neighbors": "n_neighbors",
    "n_particles": "n_particles",
    "refine": "spacing",
    "resolution": "spacing",
    "h_over_dx": "h_over_dx",
}


def compute_fits(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Power-law fits of every (part, approximation, layout, kernel, function, sweep, region).

    The x variable is the swept quantity (``h``, ``n_neighbors`` for the integral sweep, ``N`` for
    the particle sweep, the spacing for refinement sweeps, ``h/Δx`` in 2D); quantities fitted are
    ``error_abs``, ``error_rel`` and (2D) ``error_grad``.
    """
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        groups[
            (
                r["part"],
                r["approximation"],
                r["layout"],
                r["kernel"],
                r["function"],
                r["sweep"],
                r["region"],
            )
        ].append(r)
    fits = []
    for key, rs in groups.items():
        sweep = key[5]
        xname = _SWEEP_X[sweep]
        xs = [r[xname] for r in rs]
        for q in ("error_abs", "error_rel", "error_grad"):
            ys = [r[q] for r in rs]
            if not any(np.isfinite(y) for y in ys):
                continue
            f = fit_power_law(xs, ys)
            fits.append(
                dict(
                    zip(FIT_COLUMNS[:7], key),
                    quantity=q,
                    x=xname,
                    exponent=f.exponent,
                    coefficient=f.coefficient,
                    r2=f.r2,
                    n_points=f.n_points,
                    x_min=f.x_min,
                    x_max=f.x_max,
                )
            )
    return fits


def fit_lookup(fits: list[dict[str, Any]]) -> dict[tuple, dict[str, Any]]:
    """Fits keyed by (part, approximation, layout, kernel, function, sweep, region, quantity)."""
    return {
        (
            f["part"],
            f["approximation"],
            f["layout"],
            f["kernel"],
            f["function"],
            f["sweep"],
            f["region"],
            f["quantity"],
        ): f
        for f in fits
    }
