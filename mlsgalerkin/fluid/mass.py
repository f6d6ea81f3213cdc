r"""The nodal mass of the fluid's Galerkin equations and the acceleration solve.

``"lumped"`` (default)
    ``m_i = Σ_k N_i(x_k) M_k``, the row sum of the Galerkin mass matrix, computed in the same
    scatter as the internal force (:func:`~mlsgalerkin.assembly.internal_force_and_mass`). A
    lumped mass below ``MASS_FLOOR`` (a quarter) of the particle mass — a particle at the edge of
    a splash — is floored at ``M_i/4`` and counted.
``"particle"``
    ``m_i = M_i``: conserves ``Σ M v`` exactly.
``"consistent"``
    ``m_ij = Σ_k N_i(x_k) N_j(x_k) M_k``; each component of ``a`` solved by conjugate gradients
    with a Jacobi preconditioner, warm-started from the last acceleration. With MLS its
    eigenvalues reach about ``5e-6 M`` (see ``docs/theory/galerkin_fluid.md``): usable for
    experiments, not for production runs.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

__all__ = ["MASS_FLOOR", "MASS_OPTIONS", "consistent_acceleration", "floor_lumped_mass"]

MASS_FLOOR = 0.25
MASS_OPTIONS = ("lumped", "particle", "consistent")


def floor_lumped_mass(m: NDArray[np.float64], M: NDArray[np.float64], n_fluid: int) -> int:
    """Raise the fluid rows of the lumped mass ``m (n,)`` to at least ``MASS_FLOOR · M`` (in place);
    returns how many were raised."""
    floor = MASS_FLOOR * M
    low = m[:n_fluid] < floor[:n_fluid]
    if not low.any():
        return 0
    m[:n_fluid][low] = floor[:n_fluid][low]
    return int(np.count_nonzero(low))


def consistent_acceleration(table, M: NDArray[np.float64], n_fluid: int, force: NDArray[np.float64],
                            guess: NDArray[np.float64]) -> tuple[NDArray[np.float64], int]:
    """Solve ``m_c a = f`` over the fluid rows by Jacobi-preconditioned CG, per component.

    ``force, guess (n_fluid, d)``. Returns ``(a, unconverged)``: the acceleration and the number
    of components whose CG did not converge in 200 iterations (warned once per call).
    """
    from scipy.sparse import diags_array
    from scipy.sparse.linalg import cg

    from mlsgalerkin.assembly import consistent_mass

    Mc = consistent_mass(table, M).tocsr()[:n_fluid, :n_fluid]
    jacobi = diags_array(1.0 / np.maximum(Mc.diagonal(), 1e-300))
    out = np.empty_like(force)
    unconverged = 0
    for a in range(force.shape[1]):
        sol, info = cg(Mc, force[:, a], x0=guess[:, a], rtol=1e-10, atol=0.0, maxiter=200, M=jacobi)
        if info != 0:
            unconverged += 1
        out[:, a] = sol
    return out, unconverged


def warn_consistent_unconverged() -> None:
    """The warning of the first unconverged consistent-mass solve of a run."""
    warnings.warn(
        "consistent-mass CG did not converge in 200 iterations: the MLS consistent "
        "mass matrix is nearly singular (see docs/theory/galerkin_fluid.md); the "
        "acceleration is inaccurate — use mass='lumped'", RuntimeWarning, stacklevel=4)
