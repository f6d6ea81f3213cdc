r"""Operators for use inside forms, mirroring :mod:`skfem.helpers`.

Arrays follow the *component first, point last* layout of :mod:`mlsgalerkin.basis`: a scalar
field is ``(n,)``, a vector ``(dim, n)``, a tensor ``(dim, dim, n)``. All operators broadcast
over the trailing point axis, so they act on every integration entry at once.

>>> import numpy as np
>>> from mlsgalerkin.basis import DiscreteField
>>> u = DiscreteField(np.zeros((2, 3)), grad=np.arange(12.0).reshape(2, 2, 3))
>>> trace(sym_grad(u)).tolist()    # = ∂u_0/∂x_0 + ∂u_1/∂x_1 = div(u)
[9.0, 11.0, 13.0]
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["grad", "div", "dot", "ddot", "mul", "sym_grad", "transpose", "trace", "eye", "identity"]

FloatArray = NDArray[np.float64]


def grad(u: Any) -> FloatArray:
    """Gradient of a :class:`~mlsgalerkin.basis.DiscreteField`: ``(dim, n)`` or ``(dim, dim, n)``."""
    g = getattr(u, "grad", None)
    if g is None:
        raise ValueError("grad() needs a DiscreteField with a gradient (a trial/test function or "
                         "a field from basis.interpolate(u)), got a plain array")
    return g


def div(u: Any) -> FloatArray:
    """Divergence ``∂u_a/∂x_a`` of a vector field, ``(n,)``."""
    g = grad(u)
    if g.ndim < 3:
        raise ValueError("div() needs a vector field (grad of shape (dim, dim, n))")
    return np.einsum("ii...", g)


def dot(u: Any, v: Any) -> FloatArray:
    """Contraction over the first axis: ``u_i v_i``."""
    return np.einsum("i...,i...", u, v)


def ddot(A: Any, B: Any) -> FloatArray:
    """Double contraction ``A_ij B_ij``."""
    return np.einsum("ij...,ij...", A, B)


def mul(A: Any, x: Any) -> FloatArray:
    """Matrix–vector product ``A_ij x_j`` (e.g. traction ``σ n``)."""
    return np.einsum("ij...,j...->i...", A, x)


def transpose(T: Any) -> FloatArray:
    """Swap the two leading (component) axes."""
    return np.einsum("ij...->ji...", T)


def sym_grad(u: Any) -> FloatArray:
    """Symmetric gradient (small strain) ``½(∇u + ∇uᵀ)``, ``(dim, dim, n)``."""
    g = grad(u)
    return 0.5 * (g + transpose(g))


def trace(T: Any) -> FloatArray:
    """Trace ``T_ii``."""
    return np.einsum("ii...", T)


def eye(w: Any, size: int) -> FloatArray:
    """``w`` times the ``size x size`` identity: ``(size, size, *w.shape)``."""
    w = np.asarray(w, dtype=np.float64)
    out = np.zeros((size, size) + w.shape)
    for i in range(size):
        out[i, i] = w
    return out


def identity(w: Any, size: int | None = None) -> FloatArray:
    """Identity tensor with the point shape of ``w`` (``(dim, ..., n)``); ``size`` defaults to ``w.shape[0]``."""
    w = np.asarray(w)
    return eye(np.ones(w.shape[1:]), w.shape[0] if size is None else size)
