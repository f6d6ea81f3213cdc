r"""Error norms against closed-form solutions on a background Gauss quadrature.

The discrete field ``u^h = Σ_I N_I u_I`` and its **direct** gradient are evaluated at tensor
Gauss points of a fine background grid (independent of the nodal rule used to solve), so the
errors measure the approximation itself, not the solver's quadrature:

.. math::

    \|u - u^h\|_{L^2}^2 \approx \sum_q w_q |u(x_q) - u^h(x_q)|^2, \qquad
    |u - u^h|_{H^1}^2 \approx \sum_q w_q |\nabla u(x_q) - \nabla u^h(x_q)|^2,

and for elasticity the energy norm ``‖e‖_E² = ∫ ε(e):C:ε(e) dΩ = ∫ 2μ ε:ε + λ (tr ε)² dΩ``.
Relative versions divide by the same norm of the exact solution.

>>> import numpy as np
>>> from mlsgalerkin.analysis.norms import rectangle_quadrature
>>> q = rectangle_quadrature((0, 0), (2, 1), n_cells=4, n_gauss=3)
>>> q.points.shape, round(float(q.weights.sum()), 12), round(float(q.integrate(q.points[:, 0] ** 2)), 12)
((144, 2), 2.0, 2.666666666667)

Callables follow the forms' convention: ``exact(x)`` gets ``x`` of shape ``(dim, n)`` and returns
``(n,)`` (scalar) or ``(c, n)`` (vector); ``grad_exact(x)`` returns ``(dim, n)`` or
``(c, dim, n)`` with ``[a, b] = ∂u_a/∂x_b``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import ShapeTable
from mlsgalerkin.basis import MeshfreeBasis

__all__ = [
    "Quadrature",
    "rectangle_quadrature",
    "ErrorNorms",
    "l2_error",
    "h1_seminorm_error",
    "energy_error",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Quadrature:
    """Background quadrature: ``points (n, dim)`` and ``weights (n,)`` (length^dim)."""

    points: FloatArray
    weights: FloatArray

    def integrate(self, values: ArrayLike) -> float:
        """``Σ_q w_q f_q`` for per-point ``values`` ``(n,)``."""
        return float(np.dot(np.asarray(values, dtype=float), self.weights))


def rectangle_quadrature(lower: ArrayLike, upper: ArrayLike, n_cells: int | tuple[int, int],
                         n_gauss: int = 4) -> Quadrature:
    """Tensor Gauss–Legendre rule: ``n_gauss²`` points in each of ``n_cells`` (int or (nx, ny)) cells."""
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lo.shape != (2,) or hi.shape != (2,) or not (hi > lo).all():
        raise ValueError(f"need 2D corners with lower < upper, got {lower} and {upper}")
    nc = np.broadcast_to(np.asarray(n_cells, dtype=int), (2,))
    if (nc < 1).any() or int(n_gauss) < 1:
        raise ValueError(f"n_cells and n_gauss must be >= 1, got {n_cells}, {n_gauss}")
    xg, wg = np.polynomial.legendre.leggauss(int(n_gauss))
    axes, weights = [], []
    for d in range(2):
        edges = np.linspace(lo[d], hi[d], nc[d] + 1)
        half = 0.5 * np.diff(edges)
        mid = 0.5 * (edges[:-1] + edges[1:])
        axes.append((mid[:, None] + half[:, None] * xg).ravel())
        weights.append((half[:, None] * wg).ravel())
    X, Y = np.meshgrid(*axes, indexing="ij")
    W = np.outer(*weights)
    return Quadrature(np.column_stack([X.ravel(), Y.ravel()]), W.ravel())


def _as_field(name: str, value: ArrayLike, want: tuple[int, ...]) -> FloatArray:
    a = np.asarray(value, dtype=float)
    if a.shape != want:
        raise ValueError(f"{name} returned shape {a.shape}, expected {want}")
    return a


class ErrorNorms:
    """Errors of DOF vectors of ``basis`` on ``quadrature`` (shape functions built once).

    Parameters
    ----------
    basis : MeshfreeBasis
        Must know its dilation ``h`` (e.g. built by :func:`~mlsgalerkin.integration.meshfree_basis`).
    quadrature : Quadrature
        Background rule covering the domain, e.g. :func:`rectangle_quadrature`.
    """

    def __init__(self, basis: MeshfreeBasis, quadrature: Quadrature) -> None:
        if not isinstance(basis, MeshfreeBasis):
            raise ValueError(f"basis must be a MeshfreeBasis, got {type(basis).__name__}")
        if quadrature.points.ndim != 2 or quadrature.points.shape[1] != basis.dim:
            raise ValueError(
                f"quadrature points must be (n, {basis.dim}), got {quadrature.points.shape}"
            )
        self.basis = basis
        self.quadrature = quadrature
        self.table: ShapeTable = basis.shape_functions_at(quadrature.points)

    def _field(self, u: ArrayLike):
        f = self.basis.interpolate_at(self.quadrature.points, u, table=self.table)
        return np.asarray(f), f.grad

    def _value_shape(self) -> tuple[int, ...]:
        n, c = self.quadrature.points.shape[0], self.basis.n_components
        return (n,) if c == 1 else (c, n)

    def _norms(self, diff: FloatArray, ref: FloatArray, relative: bool) -> float:
        w = self.quadrature.weights
        sq = diff.reshape(-1, w.size) ** 2
        err = float(np.sqrt(np.dot(sq.sum(axis=0), w)))
        if not relative:
            return err
        norm = float(np.sqrt(np.dot((ref.reshape(-1, w.size) ** 2).sum(axis=0), w)))
        if norm == 0.0:
            raise ValueError("the exact solution has zero norm; use relative=False")
        return err / norm

    def l2(self, u: ArrayLike, exact: Callable, relative: bool = False) -> float:
        """``‖u - u^h‖_{L²}`` (or relative to ``‖u‖_{L²}``)."""
        uh, _ = self._field(u)
        ue = _as_field("exact", exact(self.quadrature.points.T), self._value_shape())
        return self._norms(uh - ue, ue, relative)

    def h1_seminorm(self, u: ArrayLike, grad_exact: Callable, relative: bool = False) -> float:
        """``|u - u^h|_{H¹} = ‖∇u - ∇u^h‖_{L²}`` (or relative to ``|u|_{H¹}``)."""
        _, gh = self._field(u)
        ge = _as_field("grad_exact", grad_exact(self.quadrature.points.T), gh.shape)
        return self._norms(gh - ge, ge, relative)

    def energy(self, u: ArrayLike, grad_exact: Callable, lam: float, mu: float,
               relative: bool = False) -> float:
        """Elastic energy norm of the error ``sqrt(∫ 2μ ε:ε + λ (tr ε)²)`` (vector bases)."""
        if self.basis.n_components != self.basis.dim:
            raise ValueError("energy() needs a vector (displacement) basis")
        _, gh = self._field(u)
        ge = _as_field("grad_exact", grad_exact(self.quadrature.points.T), gh.shape)
        w = self.quadrature.weights

        def energy_sq(g: FloatArray) -> float:
            eps = 0.5 * (g + np.swapaxes(g, 0, 1))
            tr = np.einsum("ii...", eps)
            density = 2.0 * mu * np.einsum("ij...,ij...", eps, eps) + lam * tr**2
            return float(np.dot(density, w))

        err = np.sqrt(max(energy_sq(gh - ge), 0.0))
        if not relative:
            return float(err)
        norm = np.sqrt(energy_sq(ge))
        if norm == 0.0:
            raise ValueError("the exact solution has zero energy; use relative=False")
        return float(err / norm)


def l2_error(basis: MeshfreeBasis, u: ArrayLike, exact: Callable, quadrature: Quadrature,
             relative: bool = False) -> float:
    """One-shot :meth:`ErrorNorms.l2`."""
    return ErrorNorms(basis, quadrature).l2(u, exact, relative)


def h1_seminorm_error(basis: MeshfreeBasis, u: ArrayLike, grad_exact: Callable,
                      quadrature: Quadrature, relative: bool = False) -> float:
    """One-shot :meth:`ErrorNorms.h1_seminorm`."""
    return ErrorNorms(basis, quadrature).h1_seminorm(u, grad_exact, relative)


def energy_error(basis: MeshfreeBasis, u: ArrayLike, grad_exact: Callable, quadrature: Quadrature,
                 lam: float, mu: float, relative: bool = False) -> float:
    """One-shot :meth:`ErrorNorms.energy`."""
    return ErrorNorms(basis, quadrature).energy(u, grad_exact, lam, mu, relative)
