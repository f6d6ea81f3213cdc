r"""Sub-cycled explicit central differences of a linear elastic body: one compiled call per outer step.

Inside one outer (fluid) step :math:`\Delta t` the structure takes :math:`n` sub-steps of
:math:`\delta t = \Delta t/n` in velocity-Verlet form, with the external forces
:math:`\mathbf f` (weight, contact and fluid loads) ramped linearly over the outer step,
:math:`\mathbf f(t_k) = \mathbf f_0 + (k/n)\,\Delta\mathbf f`:

.. math::

    \mathbf v \mathrel{+}= \tfrac12\delta t\,\mathbf a,\qquad
    \mathbf u \mathrel{+}= \delta t\,\mathbf v,\qquad
    \mathbf a = M^{-1}\big(\mathbf f - K(\mathbf u + a_1\mathbf v)\big) - a_0\mathbf v,\qquad
    \mathbf v \mathrel{+}= \tfrac12\delta t\,\mathbf a,

with the lumped mass :math:`M`, the stiffness :math:`K` (CSR) and Rayleigh damping
:math:`C = a_0M + a_1K` evaluated with the half-step velocity; clamped degrees of freedom keep
:math:`\mathbf a = 0`. Undamped, it is central differences (second order, symplectic), stable for
:math:`\delta t < 2/\omega_{max}`.

:func:`subcycle_linear` runs all :math:`n` sub-steps in one numba call (the CSR product inlined):
no Python between sub-steps, which is where a per-sub-step scipy product loses its time (measured
in ``benchmarks/bench_structure.py``). :func:`subcycle_linear_reference` is the numpy/scipy
version for the tests. :func:`leapfrog_step` is one undamped step of the same scheme on arrays a
script keeps itself (a run uses :class:`~mlsgalerkin.structure.steppers.CentralDifference`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numba
import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.structure.elastic import ElasticBody

__all__ = ["leapfrog_step", "subcycle_linear", "subcycle_linear_reference"]

FloatArray = NDArray[np.float64]


@numba.njit(cache=True)
def _subcycle_linear(indptr, indices, data, inv_m, fixed, f0, df, u, v, a, dt, n, a0, a1):  # pragma: no cover
    N = u.shape[0]
    w = np.empty(N)
    h = 0.5 * dt
    for k in range(n):
        ramp = (k + 1.0) / n
        for i in range(N):
            v[i] += h * a[i]
            u[i] += dt * v[i]
        for i in range(N):
            w[i] = u[i] + a1 * v[i]
        for i in range(N):
            if fixed[i]:
                a[i] = 0.0
                continue
            s = 0.0
            for k in range(indptr[i], indptr[i + 1]):
                s += data[k] * w[indices[k]]
            a[i] = (f0[i] + ramp * df[i] - s) * inv_m[i] - a0 * v[i]
            v[i] += h * a[i]


def subcycle_linear(K: sp.csr_matrix, inv_m: FloatArray, fixed: NDArray[np.bool_], f0: FloatArray, df: FloatArray,
                    u: FloatArray, v: FloatArray, a: FloatArray, dt: float, n: int, a0: float = 0.0,
                    a1: float = 0.0) -> None:
    """``n`` velocity-Verlet sub-steps of ``dt`` (s) in place on ``u, v, a (N,)`` (m, m/s, m/s²)
    under the forces ``f0 + (k/n) df`` (N) at the end of sub-step ``k`` (a ramp over the outer
    step; ``a`` must hold the acceleration at its start); ``K`` CSR (N/m), ``inv_m (N,)`` (1/kg),
    ``fixed (N,)`` the clamped degrees of freedom, Rayleigh ``a0`` (1/s), ``a1`` (s)."""
    _subcycle_linear(K.indptr, K.indices, K.data, inv_m, fixed, f0, df, u, v, a, float(dt), int(n), float(a0),
                     float(a1))


def subcycle_linear_reference(K: sp.csr_matrix, inv_m: FloatArray, fixed: NDArray[np.bool_], f0: FloatArray,
                              df: FloatArray, u: FloatArray, v: FloatArray, a: FloatArray, dt: float, n: int,
                              a0: float = 0.0, a1: float = 0.0) -> None:
    """The numpy/scipy version of :func:`subcycle_linear` (same arguments, in place)."""
    for k in range(n):
        v += 0.5 * dt * a
        u += dt * v
        a[:] = (f0 + (k + 1.0) / n * df - K @ (u + a1 * v)) * inv_m - a0 * v
        a[fixed] = 0.0
        v += 0.5 * dt * a


def leapfrog_step(body: ElasticBody, u: FloatArray, v: FloatArray, dt: float, f_ext: FloatArray | None = None) -> None:
    """One undamped central-difference step of ``dt`` (s) of the linear ``body`` in place on the
    displacement ``u (N,)`` (m) and the half-step velocity ``v (N,)`` (m/s) under external nodal
    forces ``f_ext (N,)`` (N): ``v += dt M⁻¹(f_ext − K u)``, ``u += dt v``, the clamped degrees of
    freedom held."""
    f = -body.internal_force(u)
    if f_ext is not None:
        f = f + f_ext
    a = f / body.lumped_mass
    a[body.clamped_dofs] = 0.0
    v += dt * a
    u += dt * v
