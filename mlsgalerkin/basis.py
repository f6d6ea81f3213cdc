r"""MeshfreeBasis: the approximation evaluated at an integration rule's points.

A :class:`MeshfreeBasis` plays the role of :class:`skfem.Basis`: it couples the nodes (the
geometry), the shape functions (the approximation) and an integration rule (the points,
weights and the gradients the rule uses: direct for DNI, smoothed for SCNI), so that the forms
of :mod:`mlsgalerkin.forms` can be assembled against it. Any rule-like object will do (see
:class:`MeshfreeBasis`); :func:`mlsgalerkin.integration.meshfree_basis` builds a DNI or SCNI rule
and wraps it, so this module imports nothing from :mod:`mlsgalerkin.integration`.

>>> import numpy as np
>>> from mlsgalerkin.integration import meshfree_basis, rectangle
>>> g = np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, indexing="ij"), -1).reshape(-1, 2)
>>> basis = meshfree_basis(g, h=0.3, rule="scni", domain=rectangle((0, 0), (1, 1)))
>>> basis.n_dofs, float(basis.weights.sum())
(36, 1.0)
>>> u = basis.interpolate(2.0 * g[:, 0] - g[:, 1])      # linear fields are reproduced
>>> bool(np.allclose(u.grad[:, 0], [2.0, -1.0]))
True

Layouts
-------
Fields at ``n`` points are stored *component first, point last* (scikit-fem's convention):

==========================  =========================  ==================================
field                        value                      ``grad`` (``grad[a, b] = ∂u_a/∂x_b``)
==========================  =========================  ==================================
scalar (``n_components=1``)  ``(n,)``                   ``(dim, n)``
vector (``n_components=d``)  ``(dim, n)``               ``(dim, dim, n)``
==========================  =========================  ==================================

DOF vectors are node-major: ``dof = node * n_components + component``, so
``u.reshape(n_nodes, n_components)`` gives the nodal values.
"""

from __future__ import annotations

import logging
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.approximation import ShapeTable, shape_functions
from mlsgalerkin.neighbors import as_coordinates

__all__ = ["DiscreteField", "MeshfreeBasis"]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]


class DiscreteField(np.ndarray):
    """Values of a field at points, carrying its gradient in ``.grad`` (like skfem's).

    The array itself is the value (``(n,)`` scalar, ``(dim, n)`` vector); ``grad`` is
    ``(dim, n)`` or ``(dim, dim, n)``. Arithmetic on the field returns a plain ``ndarray``
    (the gradient no longer applies), so ``u * v`` inside a form is an ordinary product.
    """

    grad: FloatArray | None

    def __new__(cls, value: ArrayLike, grad: ArrayLike | None = None) -> "DiscreteField":
        obj = np.asarray(value, dtype=np.float64).view(cls)
        obj.grad = None if grad is None else np.asarray(grad, dtype=np.float64)
        return obj

    def __array_finalize__(self, obj: Any) -> None:
        if obj is None:
            return
        self.grad = getattr(obj, "grad", None)

    def __array_wrap__(self, out_arr, context=None, return_scalar=False):  # noqa: D105
        # results of ufuncs are plain arrays: the gradient does not survive arithmetic
        out = np.asarray(out_arr)
        return out[()] if return_scalar else out

    def __getitem__(self, key):  # indexing gives plain values, as in skfem
        return np.asarray(self)[key]

    @property
    def value(self) -> FloatArray:
        """The values as a plain ``ndarray``."""
        return np.asarray(self)

    def take_points(self, index: NDArray[np.integer]) -> "DiscreteField":
        """The field at a subset/repetition of its points (last axis), gradient included."""
        grad = None if self.grad is None else self.grad[..., index]
        return DiscreteField(np.asarray(self)[..., index], grad)

    def __repr__(self) -> str:
        g = None if self.grad is None else self.grad.shape
        return f"DiscreteField(shape={self.shape}, grad shape={g})"


def _rule_arrays(rule: Any) -> tuple[FloatArray, FloatArray, ShapeTable, str]:
    missing = [a for a in ("points", "weights", "table") if not hasattr(rule, a)]
    if missing:
        raise ValueError(
            f"rule must provide points, weights and table (a NodalIntegration); "
            f"{type(rule).__name__} lacks {', '.join(missing)}"
        )
    return (np.asarray(rule.points, dtype=np.float64), np.asarray(rule.weights, dtype=np.float64),
            rule.table, str(getattr(rule, "name", type(rule).__name__)))


class MeshfreeBasis:
    """Shape functions of ``nodes`` evaluated at the points of an integration rule.

    Parameters
    ----------
    nodes : (n_nodes, dim) float array
        Node coordinates (length units).
    rule : NodalIntegration
        Any object with ``points (n_points, dim)``, ``weights (n_points,)`` (length^dim) and a
        :class:`~mlsgalerkin.approximation.ShapeTable` ``table`` of ``N_I`` and the rule's
        ``∇N_I`` at those points, e.g. from
        :func:`~mlsgalerkin.integration.stabilized_conforming_nodal_integration`.
    n_components : int
        1 for a scalar field, ``dim`` for a vector field (displacement).
    h : float or (n_nodes,) float array, optional
        The dilation the table was built with. Needed only to evaluate the shape functions at
        other points (:meth:`shape_functions_at`: boundary quadrature, error norms).
    shape_kw : dict, optional
        Keyword arguments of :func:`~mlsgalerkin.shape_functions` for those evaluations.
        Default: ``kernel``, ``basis`` (order) and ``method`` read from the table. ``method=
        "rkpm"`` also needs ``volumes``, which the table does not record.

    Attributes
    ----------
    nodes, points, weights, table, n_components, name
    """

    def __init__(
        self,
        nodes: ArrayLike,
        rule: Any,
        n_components: int = 1,
        *,
        h: ArrayLike | None = None,
        shape_kw: dict | None = None,
    ) -> None:
        self.nodes = as_coordinates("nodes", nodes)
        points, weights, table, name = _rule_arrays(rule)
        n_nodes, dim = self.nodes.shape
        if points.ndim != 2 or points.shape[1] != dim:
            raise ValueError(f"rule points must have shape (n_points, {dim}), got {points.shape}")
        n_points = points.shape[0]
        if weights.shape != (n_points,):
            raise ValueError(f"rule weights must have shape ({n_points},), got {weights.shape}")
        if not np.isfinite(weights).all():
            raise ValueError("rule weights must be finite")
        if not isinstance(table, ShapeTable):
            raise ValueError(f"rule.table must be a ShapeTable, got {type(table).__name__}")
        if table.n_points != n_points or table.n_nodes != n_nodes:
            raise ValueError(
                f"rule table is {table.n_points} points x {table.n_nodes} nodes, expected "
                f"{n_points} x {n_nodes}"
            )
        if n_components not in (1, dim):
            raise ValueError(
                f"n_components must be 1 (scalar) or {dim} (vector), got {n_components!r}"
            )
        self.points = points
        self.weights = weights
        self.table = table
        self.name = name
        self.n_components = int(n_components)
        self.h = None if h is None else np.asarray(h, dtype=np.float64)
        if shape_kw is None:
            shape_kw = {"kernel": table.kernel, "basis": table.requested_order,
                        "method": table.method}
        self.shape_kw = dict(shape_kw)
        # per (test basis) cache of the expanded (point, trial pair, test pair) index arrays
        self._triples: dict[int, tuple[Any, Any]] = {}

    # ---- sizes --------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.nodes.shape[1]

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    @property
    def n_points(self) -> int:
        return self.points.shape[0]

    @property
    def n_dofs(self) -> int:
        return self.n_nodes * self.n_components

    @property
    def is_vector(self) -> bool:
        return self.n_components > 1

    def nodal_dofs(self) -> NDArray[np.int64]:
        """DOF numbers ``(n_nodes, n_components)``: ``dofs[I, c] = I * n_components + c``."""
        return np.arange(self.n_dofs, dtype=np.int64).reshape(self.n_nodes, self.n_components)

    def __repr__(self) -> str:
        kind = "scalar" if self.n_components == 1 else f"{self.n_components}-vector"
        return (f"{type(self).__name__}({self.name}, {self.n_nodes} nodes, {self.n_points} points, "
                f"{kind}, {self.n_dofs} dofs)")

    # ---- fields -------------------------------------------------------------------------
    def nodal_values(self, u: ArrayLike) -> FloatArray:
        """DOF vector ``(n_dofs,)`` (or ``(n_nodes, n_components)``) as ``(n_nodes,)``/``(n_nodes, c)``."""
        a = np.asarray(u, dtype=np.float64)
        c = self.n_components
        if a.shape == (self.n_dofs,):
            return a if c == 1 else a.reshape(self.n_nodes, c)
        if c > 1 and a.shape == (self.n_nodes, c):
            return a
        want = f"({self.n_dofs},)" + (f" or ({self.n_nodes}, {c})" if c > 1 else "")
        raise ValueError(f"DOF vector must have shape {want}, got {a.shape}")

    def dof_vector(self, nodal: ArrayLike) -> FloatArray:
        """Inverse of :meth:`nodal_values`: ``(n_nodes, c)`` nodal values -> ``(n_dofs,)``."""
        return self.nodal_values(nodal).reshape(-1).copy()

    @staticmethod
    def _field_from_table(table: ShapeTable, U: FloatArray) -> DiscreteField:
        value = table.interpolate(U)  # (n,) or (n, c)
        grad = table.gradient(U)      # (n, dim) or (n, c, dim)
        return DiscreteField(np.moveaxis(value, 0, -1), np.moveaxis(grad, 0, -1))

    def interpolate(self, u: ArrayLike) -> DiscreteField:
        """The field of DOF vector ``u`` at the integration points, with the rule's gradient.

        Returns a :class:`DiscreteField`: value ``(n_points,)`` / ``(dim, n_points)`` and
        ``grad`` ``(dim, n_points)`` / ``(dim, dim, n_points)``. For SCNI the gradient is the
        smoothed one. Pass the result to ``form.assemble(basis, name=field)``.
        """
        return self._field_from_table(self.table, self.nodal_values(u))

    def shape_functions_at(self, points: ArrayLike, **overrides: Any) -> ShapeTable:
        """Shape functions and their *direct* gradients at arbitrary ``points (n, dim)``."""
        if self.h is None:
            raise ValueError(
                "this basis does not know its dilation h: build it with MeshfreeBasis(..., h=...) "
                "or meshfree_basis() to evaluate shape functions at other points"
            )
        kw = {**self.shape_kw, **overrides}
        if kw.get("method") == "rkpm" and kw.get("volumes") is None:
            raise ValueError(
                "method='rkpm' needs volumes: pass shape_kw={'volumes': ...} to the basis"
            )
        return shape_functions(as_coordinates("points", points, self.dim), self.nodes, self.h, **kw)

    def interpolate_at(self, points: ArrayLike, u: ArrayLike,
                       table: ShapeTable | None = None) -> DiscreteField:
        """Field of ``u`` at arbitrary ``points`` with direct gradients (layout as :meth:`interpolate`)."""
        table = self.shape_functions_at(points) if table is None else table
        return self._field_from_table(table, self.nodal_values(u))

    # ---- data handed to forms ---------------------------------------------------------
    @cached_property
    def cell_size(self) -> FloatArray:
        """Local length scale at each integration point, ``weights ** (1/dim)``, ``(n_points,)``."""
        return np.abs(self.weights) ** (1.0 / self.dim)

    def default_parameters(self) -> dict[str, FloatArray]:
        """Per-point data every form receives in ``w``: ``x (dim, n_points)``, ``h (n_points,)``."""
        return {"x": self.points.T, "h": self.cell_size}

    @cached_property
    def pair_points(self) -> NDArray[np.int64]:
        """Integration point of each table pair, ``(n_pairs,)``."""
        return self.table.rows()
