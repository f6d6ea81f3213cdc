r"""Forms for the Poisson problem ``-∇·(k ∇u) = f`` (scalar bases).

>>> import numpy as np
>>> from mlsgalerkin.integration import meshfree_basis, rectangle
>>> from mlsgalerkin.models.poisson import laplace, source
>>> g = np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, indexing="ij"), -1).reshape(-1, 2)
>>> basis = meshfree_basis(g, h=0.3, domain=rectangle((0, 0), (1, 1)))
>>> K = laplace.assemble(basis)
>>> f = source(lambda x: 1.0 + 0.0 * x[0]).assemble(basis)
>>> round(float(f.sum()), 12), float(abs(K @ np.ones(36)).max()) < 1e-12   # ∫1 = 1; K 1 = 0
(1.0, True)

Callables receive the coordinates ``x`` with shape ``(dim, n)`` (``x[0]``, ``x[1]``) and return
``(n,)`` values, as in scikit-fem.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from mlsgalerkin.forms import BilinearForm, LinearForm
from mlsgalerkin.helpers import dot, grad

__all__ = ["laplace", "mass", "unit_load", "source", "flux"]


@BilinearForm
def laplace(u, v, w):
    r"""``∫ ∇u · ∇v dΩ``."""
    return dot(grad(u), grad(v))


@BilinearForm
def mass(u, v, w):
    r"""``∫ u v dΩ``."""
    return u * v


@LinearForm
def unit_load(v, w):
    r"""``∫ v dΩ``."""
    return np.asarray(v) * 1.0


def source(f: float | Callable) -> LinearForm:
    r"""``∫ f v dΩ`` for a constant or a callable ``f(x)``, ``x`` of shape ``(dim, n)``."""
    if callable(f):
        def load(v, w):
            return np.asarray(f(w.x), dtype=float) * v
    else:
        value = float(f)

        def load(v, w):
            return value * np.asarray(v)
    load.__name__ = "source"
    return LinearForm(load)


def flux(u):
    r"""Flux ``∇u`` of a scalar field, the operator Nitsche's method needs (``k = 1``)."""
    return grad(u)
