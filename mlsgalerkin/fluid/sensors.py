r"""Pressure sensors: the pressure of the particles at given points, as a laboratory transducer
would read it.

A sensor point ``x`` (on a wall face, say) reads the Shepard average of the particle
pressures around it, fluid and wall particles alike (the wall particles carry the pressure
the wall model extrapolates to them, so a point on the wall face sees a full kernel support):

.. math::
    p(\mathbf x) = \frac{\sum_j p_j\,V_j\,W(|\mathbf x - \mathbf x_j|, h_j)}
                        {\sum_j V_j\,W(|\mathbf x - \mathbf x_j|, h_j)},
    \qquad V_j = M_j/\rho_j,

and ``p = 0`` (dry) when no *fluid* particle is within a kernel support of ``x``. A
transducer of finite size reads the mean over points spread along its face
(:func:`sensor_points`). Evaluated with numpy over the particles inside the points' bounding
box (a few hundred), so a sensor costs little beside a step.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.kernels import Kernel, get_kernel

__all__ = ["pressure_at", "sensor_points"]


def pressure_at(s: FluidState, points: ArrayLike, kernel: str | Kernel = "cubic_spline") -> NDArray[np.float64]:
    """Shepard pressure ``(k,)`` (Pa) at ``points (k, d)`` (m) from the particles of ``s``
    (module docstring); 0 where no fluid particle is within a kernel support."""
    kern = get_kernel(kernel)
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    dim = s.x.shape[1]
    reach = kern.support * float(s.h.max())
    lo, hi = pts.min(axis=0) - reach, pts.max(axis=0) + reach
    near = np.flatnonzero(np.all((s.x >= lo) & (s.x <= hi), axis=1))
    out = np.zeros(len(pts))
    if near.size == 0:
        return out
    r = np.linalg.norm(pts[:, None, :] - s.x[near][None, :, :], axis=2)          # (k, m)
    w = kern.value(r, s.h[near][None, :], dim) * (s.M[near] / s.rho[near])[None, :]
    wet = (w[:, near < s.n_fluid] > 0).any(axis=1)
    total = w.sum(axis=1)
    ok = wet & (total > 0)
    out[ok] = (w[ok] @ s.p[near]) / total[ok]
    return out


def sensor_points(face: ArrayLike, lower: float, upper: float, axis: int = 1, count: int = 5) -> NDArray[np.float64]:
    """``count`` points ``(count, d)`` spread evenly (cell centres) over a transducer's face:
    the coordinate ``axis`` from ``lower`` to ``upper`` (m), the others those of ``face``."""
    base = np.asarray(face, dtype=float)
    pts = np.tile(base, (count, 1))
    pts[:, axis] = lower + (np.arange(count) + 0.5) * (upper - lower) / count
    return pts
