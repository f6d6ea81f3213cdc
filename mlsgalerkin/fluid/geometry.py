"""Checks of a fluid scene's geometry before any work: overlapping bodies, fluid outside its walls.

Particles of a lattice sit one spacing ``Δx`` apart, and a wall's first layer half a spacing
outside the fluid's boundary, so in a sound scene no fluid particle is closer than about ``Δx``
to another particle. Two fluid particles (of one body or of two) closer than ``Δx/2`` are a
duplicated or overlapping body — its mass counted twice; a fluid particle closer than ``Δx/2``
to a wall particle sits inside the wall. A fluid particle outside the bounding box of the wall
particles (by more than ``Δx/2``) is outside its container — except above it, against gravity
(a drop falling into an open tank). Wall bodies may overlap each other (a paddle sliding over a
tank wall).
"""

from __future__ import annotations

import numpy as np

from mlsgalerkin.fluid.bodies import FluidBody, WallBody
from mlsgalerkin.neighbors import find_neighbors

__all__ = ["geometry_problems"]


def _where(x: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.4g}" for v in x) + ")"


def geometry_problems(fluids: list[FluidBody], walls: list[WallBody], gravity: np.ndarray | None = None) -> list[str]:
    """Every geometric problem of these bodies (empty if none); see the module docstring.
    ``gravity (d,)``: fluid above the walls (against gravity) is allowed."""
    if not fluids:
        return []
    out: list[str] = []
    dx = fluids[0].spacing
    x = np.concatenate([b.positions for b in fluids])
    owner = np.concatenate([np.full(b.n, k) for k, b in enumerate(fluids)])
    close = find_neighbors(x, x, radius=0.5 * dx)
    rows = np.repeat(np.arange(x.shape[0]), np.diff(close.indptr))
    cols = close.indices.astype(np.int64)
    pairs = rows < cols
    if pairs.any():
        i, j = rows[pairs], cols[pairs]
        bodies = sorted({(fluids[owner[a]].name, fluids[owner[b]].name) for a, b in zip(i, j)})
        names = ", ".join(f"{a!r} and {b!r}" if a != b else f"{a!r} with itself" for a, b in bodies)
        out.append(f"{len(i)} pairs of fluid particles closer than half a spacing ({names}), first at "
                   f"{_where(x[i[0]])}: bodies overlap or are listed twice, so their mass counts twice; "
                   "remove the duplicate or move the bodies apart")
    if walls:
        w = np.concatenate([b.positions for b in walls])
        near = find_neighbors(x, w, radius=0.5 * dx)
        inside = np.flatnonzero(np.diff(near.indptr) > 0)
        if inside.size:
            out.append(f"{inside.size} fluid particles lie within half a spacing of wall particles (first at "
                       f"{_where(x[inside[0]])}, body {fluids[owner[inside[0]]].name!r}): the fluid reaches into "
                       "the walls; make the walls enclose the fluid with a gap of half a spacing (wall_box does)")
        lo, hi = w.min(axis=0) - 0.5 * dx, w.max(axis=0) + 0.5 * dx
        below, above = x < lo, x > hi
        if gravity is not None and np.any(gravity != 0):
            up = int(np.argmax(np.abs(gravity)))
            (above if gravity[up] < 0 else below)[:, up] = False  # open to the sky
        outside = np.flatnonzero(np.any(below | above, axis=1))
        if outside.size:
            out.append(f"{outside.size} fluid particles lie outside the walls (first at {_where(x[outside[0]])}, "
                       f"body {fluids[owner[outside[0]]].name!r}; the walls span {np.round(lo + 0.5 * dx, 6).tolist()}"
                       f" to {np.round(hi - 0.5 * dx, 6).tolist()} m): move the fluid inside its container or "
                       "enlarge the walls")
    return out
