r"""Scaled, shifted monomial bases :math:`\mathbf P(\boldsymbol\xi)` for MLS/RKPM.

With :math:`\boldsymbol\xi_j = (\mathbf x_j - \mathbf x)/s` the basis is ordered by degree, so a
lower order is a *prefix* of a higher one (the fallback policy relies on this):

=====  ==================================  ===========================================
 dim   linear (m)                          quadratic (m)
=====  ==================================  ===========================================
 1     1, ξ (2)                            + ξ² (3)
 2     1, ξ₁, ξ₂ (3)                       + ξ₁², ξ₁ξ₂, ξ₂² (6)
 3     1, ξ₁, ξ₂, ξ₃ (4)                   + ξ₁², ξ₁ξ₂, ξ₁ξ₃, ξ₂², ξ₂ξ₃, ξ₃² (10)
=====  ==================================  ===========================================

Example
-------
>>> from mlsgalerkin.polynomials import monomial_exponents, basis_size
>>> basis_size(2, 2), monomial_exponents(2, 1).tolist()
(6, [[0, 0], [1, 0], [0, 1]])
"""

from __future__ import annotations

import itertools

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["BASIS_ORDERS", "basis_order", "basis_size", "monomial_exponents", "evaluate_basis"]

#: Basis names and their polynomial order.
BASIS_ORDERS: dict[str, int] = {"constant": 0, "linear": 1, "quadratic": 2}


def basis_order(basis: str | int) -> int:
    """Polynomial order of a basis given by name (``"linear"``) or as an integer 0-2."""
    if isinstance(basis, (int, np.integer)) and 0 <= int(basis) <= 2:
        return int(basis)
    try:
        return BASIS_ORDERS[basis]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown basis {basis!r}; choose one of {', '.join(BASIS_ORDERS)}"
        ) from None


def basis_size(dim: int, order: int) -> int:
    """Number of monomials ``m`` of total degree <= ``order`` in ``dim`` dimensions."""
    from math import comb

    return comb(dim + order, order)


def monomial_exponents(dim: int, order: int) -> NDArray[np.int64]:
    """Exponents ``(m, dim)`` of the monomials, ordered by total degree."""
    rows: list[tuple[int, ...]] = []
    for degree in range(order + 1):
        block = [
            e for e in itertools.product(range(degree + 1), repeat=dim) if sum(e) == degree
        ]
        rows.extend(sorted(block, reverse=True))
    return np.array(rows, dtype=np.int64).reshape(-1, dim)


@numba.njit(cache=True, inline="always")
def evaluate_basis(xi, exps, m, out):
    """Fill ``out[:m]`` with the monomials ``prod_k xi[k]**exps[a, k]`` (no allocation)."""
    dim = xi.shape[0]
    for a in range(m):
        v = 1.0
        for k in range(dim):
            e = exps[a, k]
            if e == 1:
                v *= xi[k]
            elif e == 2:
                v *= xi[k] * xi[k]
        out[a] = v


def evaluate_basis_numpy(xi: NDArray[np.float64], order: int) -> NDArray[np.float64]:
    """Reference: basis values ``(n, m)`` for offsets ``xi`` of shape ``(n, dim)``."""
    xi = np.atleast_2d(xi)
    exps = monomial_exponents(xi.shape[1], order)
    return np.prod(xi[:, None, :] ** exps[None, :, :], axis=2)
