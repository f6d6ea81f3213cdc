r"""Weak essential conditions (Nitsche, penalty) and natural loads on a boundary quadrature.

MLS/RKPM shape functions are not interpolating (``N_J(x_I) ≠ δ_IJ``), so prescribed values can
not be set on DOFs as in finite elements. They are imposed weakly on the
boundary Gauss points of :func:`~mlsgalerkin.integration.boundary_basis` instead.

Nitsche's method (symmetric; Nitsche 1971)
------------------------------------------
For ``-∇·F(u) = f`` with flux ``F`` (``∇u`` for Poisson, ``σ(u)`` for elasticity) and
``u = g`` on ``Γ_D``:

.. math::

    a(u, v) + \int_{Γ_D}\Big[-(F(u)n)\cdot v - (F(v)n)\cdot u + \frac{βM}{h}\,u\cdot v\Big]dΓ
    = l(v) + \int_{Γ_D}\Big[-(F(v)n)\cdot g + \frac{βM}{h}\,g\cdot v\Big]dΓ .

It is variationally consistent (the exact solution satisfies it), symmetric, and coercive when
``β > 2 C_I``, with ``C_I`` the inverse-estimate constant in
``h ||F(v)n||²_Γ ≤ C_I M a(v, v)``.

Choice of the penalty ``β M / h`` (``nitsche``): ``M`` (``modulus``) is the material scale
(1 or the conductivity for Poisson; ``E`` for elasticity), so that the penalty term has the
units of the consistency terms (modulus / length); ``h`` is a local nodal spacing, so the
parameter does not need retuning under refinement. ``β = 100`` (dimensionless) is the default.

``β > 2 C_I`` is sufficient for coercivity; :func:`nitsche_inverse_constant` measures ``C_I`` for
a given basis. With direct boundary gradients ``C_I`` grows with the dilation, with ν (λ
dominates σ: use ``M = λ + 2μ`` near incompressibility) and, on perturbed nodes, with
refinement, because SCNI's smoothed domain energy does not control pointwise direct gradients on
the boundary. Recommendation: keep ``gradients="rule"``, the default of
:func:`~mlsgalerkin.integration.boundary_basis` for SCNI bases: it keeps ``C_I`` of order one
whatever the dilation or refinement, so the default ``β = 100`` is safe, and the patch test stays
exact. Nitsche's error is insensitive to ``β`` once stable; the conditioning grows linearly with
it. Measured ``C_I``: ``docs/theory/galerkin_nodal_integration.md`` §3.

Penalty method
--------------
``(βM/h)∫u·v`` and ``(βM/h)∫g·v`` only: simple and symmetric but not consistent (the flux
terms are missing), so the error falls like ``1/β`` but never reaches round-off, even for a
linear solution: the conditioning, which grows like ``β``, stalls it first. Default ``β = 1e4``:
close to the end of the ``1/β`` range, without ruining the conditioning. Measured errors:
``docs/theory/galerkin_nodal_integration.md`` §3.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.forms import BilinearForm, LinearForm
from mlsgalerkin.helpers import dot, grad, mul
from mlsgalerkin.integration.boundary import BoundaryBasis

if TYPE_CHECKING:
    from scipy.sparse import csr_array

__all__ = [
    "nitsche",
    "nitsche_inverse_constant",
    "penalty",
    "neumann_load",
]

FloatArray = NDArray[np.float64]


# --------------------------------------------------------------------------------------
# prescribed data at boundary points
# --------------------------------------------------------------------------------------


def _boundary_values(boundary: BoundaryBasis, g: Any, name: str) -> FloatArray:
    """``g`` as per-point values ``(n,)`` (scalar basis) or ``(c, n)`` (vector basis)."""
    n, c = boundary.n_points, boundary.n_components
    want = (n,) if c == 1 else (c, n)
    if g is None:
        return np.zeros(want)
    a = np.asarray(g(boundary.points.T), dtype=float) if callable(g) else np.asarray(g, dtype=float)
    if a.shape == want:
        return a
    if a.ndim == 0 or (c > 1 and a.shape == (c,)):
        return np.broadcast_to(a[..., None] if a.ndim else a, want).copy()
    raise ValueError(
        f"{name} must be a constant, a callable x (dim, n) -> {want}, or per-point values of shape "
        f"{want} at the {n} boundary points; got shape {a.shape}"
    )


def _check_boundary(boundary: Any) -> BoundaryBasis:
    if not isinstance(boundary, BoundaryBasis):
        raise ValueError(
            f"expected a BoundaryBasis from boundary_basis(), got {type(boundary).__name__}"
        )
    return boundary


def _mask(boundary: BoundaryBasis, components: Sequence[int] | None) -> FloatArray | None:
    """Component mask ``(c, 1)`` for vector bases (None: all components / scalar basis)."""
    if components is None:
        return None
    c = boundary.n_components
    if c == 1:
        raise ValueError("components= only applies to vector bases")
    comps = [int(i) for i in np.atleast_1d(components)]
    if not comps or any(not 0 <= i < c for i in comps):
        raise ValueError(f"components must be indices in 0..{c - 1}, got {list(components)}")
    m = np.zeros((c, 1))
    m[comps] = 1.0
    return m


def _coefficient(name: str, value: float) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be positive and finite, got {value}")
    return value


def _normal_flux(F: FloatArray, n: FloatArray) -> FloatArray:
    """``F n``: ``(dim, e)`` flux -> ``(e,)``; ``(c, dim, e)`` stress -> ``(c, e)``."""
    if F.ndim == n.ndim:
        return dot(F, n)
    if F.ndim == n.ndim + 1:
        return mul(F, n)
    raise ValueError(f"flux has shape {F.shape}; expected (dim, e) or (c, dim, e)")


def _inner(a: FloatArray, b: FloatArray) -> FloatArray:
    return a * b if a.ndim == 1 else dot(a, b)


# --------------------------------------------------------------------------------------
# essential and natural boundary conditions
# --------------------------------------------------------------------------------------


def nitsche(
    boundary: BoundaryBasis,
    g: Any = None,
    *,
    flux: Callable | None = None,
    modulus: float = 1.0,
    beta: float = 100.0,
    components: Sequence[int] | None = None,
) -> tuple[csr_array, FloatArray]:
    r"""Symmetric Nitsche terms for ``u = g`` on the points of ``boundary``.

    Parameters
    ----------
    boundary : BoundaryBasis
    g : None, constant, callable ``x (dim, n) -> (n,)`` / ``(c, n)``, or per-point values
        Prescribed value (None: homogeneous).
    flux : callable ``u -> F(u)``
        ``(dim, e)`` for scalars (default ``∇u``), ``(c, dim, e)`` for vectors, e.g.
        :func:`mlsgalerkin.models.elasticity.stress` ``(lam, mu)``.
    modulus : float
        Material scale ``M`` of the penalty ``β M / h`` (``E`` for elasticity).
    beta : float
        Dimensionless Nitsche parameter (default 100; see the module docstring).
    components : sequence of int, optional
        Vector bases: constrain only these components (e.g. ``[0]`` for ``u_x = g_x``); the
        others keep their natural condition.

    Returns
    -------
    K : scipy.sparse.csr_array ``(n_dofs, n_dofs)``, symmetric; add to the stiffness matrix.
    f : (n_dofs,) float array; add to the load vector.
    """
    b = _check_boundary(boundary)
    beta = _coefficient("beta", beta)
    modulus = _coefficient("modulus", modulus)
    if flux is None:
        if b.is_vector:
            raise ValueError("vector bases need flux=, e.g. flux=elasticity.stress(lam, mu)")
        flux = grad
    P = _mask(b, components)
    gv = _boundary_values(b, g, "g")
    pen = beta * modulus

    def proj(a):
        return a if P is None else P * a

    def nitsche_lhs(u, v, w):
        Pu, Pv = proj(np.asarray(u)), proj(np.asarray(v))
        return (-_inner(_normal_flux(flux(u), w.n), Pv) - _inner(_normal_flux(flux(v), w.n), Pu)
                + pen / w.h * _inner(Pu, Pv))

    def nitsche_rhs(v, w):
        Pg, Pv = proj(w.g), proj(np.asarray(v))
        return -_inner(_normal_flux(flux(v), w.n), Pg) + pen / w.h * _inner(Pg, Pv)

    return BilinearForm(nitsche_lhs).assemble(b), LinearForm(nitsche_rhs).assemble(b, g=gv)


def nitsche_inverse_constant(
    boundary: BoundaryBasis,
    stiffness: Any,
    *,
    flux: Callable | None = None,
    modulus: float = 1.0,
) -> float:
    r"""Measured inverse-estimate constant ``C_I = max_v (h/M)‖F(v)n‖²_Γ / a(v, v)`` (dense; small problems).

    Symmetric Nitsche is coercive for ``β > 2 C_I`` (Young's inequality on the flux terms).
    ``C_I`` depends on the dilation in units of the nodal spacing, the kernel, the rule and the
    boundary gradients; on regular nodes not on the refinement level, on perturbed nodes with
    direct gradients it grows slowly with the node count (measured values:
    ``docs/theory/galerkin_nodal_integration.md`` §3).
    ``stiffness`` is the assembled domain matrix ``a`` (its null space, constants or rigid
    motions, carries no flux and is regularised away). Dense generalized eigenproblem: small
    node sets only.
    """
    import scipy.linalg

    b = _check_boundary(boundary)
    modulus = _coefficient("modulus", modulus)
    if flux is None:
        if b.is_vector:
            raise ValueError("vector bases need flux=, e.g. flux=elasticity.stress(lam, mu)")
        flux = grad
    if stiffness.shape != (b.n_dofs, b.n_dofs):
        raise ValueError(f"stiffness must be ({b.n_dofs}, {b.n_dofs}), got {stiffness.shape}")
    if b.n_dofs > 4000:
        raise ValueError(
            f"{b.n_dofs} DOFs is too many for a dense eigenvalue problem; use a coarser node set"
        )

    def flux_flux(u, v, w):
        return w.h / modulus * _inner(_normal_flux(flux(u), w.n), _normal_flux(flux(v), w.n))

    B = BilinearForm(flux_flux).assemble(b).toarray()
    K = stiffness.toarray() if hasattr(stiffness, "toarray") else np.asarray(stiffness, dtype=float)
    K = 0.5 * (K + K.T)
    shift = 1e-10 * float(np.abs(K).max())
    n = b.n_dofs
    top = scipy.linalg.eigh(B, K + shift * np.eye(n), eigvals_only=True,
                            subset_by_index=[n - 1, n - 1])
    return float(top[0])


def penalty(
    boundary: BoundaryBasis,
    g: Any = None,
    *,
    modulus: float = 1.0,
    beta: float = 1e4,
    components: Sequence[int] | None = None,
) -> tuple[csr_array, FloatArray]:
    r"""Penalty terms ``(βM/h)∫u·v`` and ``(βM/h)∫g·v`` for ``u = g`` (not consistent: error ``O(1/β)``).

    Arguments as :func:`nitsche`; returns ``(K, f)`` to add to the system.
    """
    b = _check_boundary(boundary)
    beta = _coefficient("beta", beta)
    modulus = _coefficient("modulus", modulus)
    P = _mask(b, components)
    gv = _boundary_values(b, g, "g")
    pen = beta * modulus

    def proj(a):
        return a if P is None else P * a

    def penalty_lhs(u, v, w):
        return pen / w.h * _inner(proj(np.asarray(u)), proj(np.asarray(v)))

    def penalty_rhs(v, w):
        return pen / w.h * _inner(proj(w.g), proj(np.asarray(v)))

    return BilinearForm(penalty_lhs).assemble(b), LinearForm(penalty_rhs).assemble(b, g=gv)


def neumann_load(boundary: BoundaryBasis, t: Any) -> FloatArray:
    r"""Natural-boundary load ``∫_Γ t·v dΓ``: traction ``t`` (N/m², vector) or flux ``q`` (scalar).

    ``t``: constant, callable ``x (dim, n) -> (n,)`` / ``(c, n)``, or per-point values. Use the
    same ``segments="cells"`` quadrature as the SCNI rule for exact patch tests.
    """
    b = _check_boundary(boundary)
    tv = _boundary_values(b, t, "t")

    def neumann(v, w):
        return _inner(w.t, np.asarray(v))

    return LinearForm(neumann).assemble(b, t=tv)
