"""Selecting rows of the kernel study for the report's tables and figures."""

from __future__ import annotations

from typing import Any

import numpy as np

from mlsgalerkin.studies.figures import PLOT_FLOOR

__all__ = ["PLOT_FLOOR", "select_rows", "xy_points"]


def select_rows(rows: list[dict[str, Any]], **sel: Any) -> list[dict[str, Any]]:
    """The rows whose fields equal every ``key=value`` of ``sel``."""
    return [r for r in rows if all(r[k] == v for k, v in sel.items())]


def xy_points(rs: list[dict[str, Any]], xname: str, yname: str) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` of the rows with a finite ``yname``, sorted by x; y clipped to
    :data:`PLOT_FLOOR`."""
    pairs = sorted(
        (r[xname], r[yname]) for r in rs if r[yname] is not None and np.isfinite(r[yname])
    )
    if not pairs:
        return np.array([]), np.array([])
    x, y = map(np.asarray, zip(*pairs))
    return x, np.maximum(y, PLOT_FLOOR)
