r"""Bilinear and linear forms with scikit-fem's call style, assembled on a :class:`MeshfreeBasis`.

>>> import numpy as np
>>> from mlsgalerkin.forms import BilinearForm, LinearForm
>>> from mlsgalerkin.helpers import dot, grad
>>> from mlsgalerkin.integration import meshfree_basis, rectangle
>>> g = np.stack(np.meshgrid(*[np.linspace(0, 1, 6)] * 2, indexing="ij"), -1).reshape(-1, 2)
>>> basis = meshfree_basis(g, h=0.3, rule="scni", domain=rectangle((0, 0), (1, 1)))
>>> @BilinearForm
... def laplace(u, v, w):
...     return dot(grad(u), grad(v))
>>> @LinearForm
... def load(v, w):
...     return w.x[0] * v                      # w.x: integration-point coordinates (dim, n)
>>> K, f = laplace.assemble(basis), load.assemble(basis)
>>> K.shape, round(float(f.sum()), 12)         # Σ_I N_I = 1, so Σ f = ∫ x dΩ = 1/2
((36, 36), 0.5)

How assembly works
------------------
A nodal rule has points ``k`` with weights ``w_k`` and, at each point, a neighbour list of the
nodes whose shape functions do not vanish there. A bilinear form is evaluated **once** on flat
arrays over every triple ``(k, j, i)`` with trial node ``j`` and test node ``i`` both in ``k``'s
neighbour list (``Σ_k n_k²`` entries), multiplied by ``w_k`` and summed into the sparse pattern

.. math:: K_{ij} = \sum_k w_k\, a\big(N_j, N_i; \mathbf x_k\big).

The triple index arrays and the entry -> CSR-slot map are built once per (trial, test) basis
pair and cached on the trial basis; repeated assemblies (new coefficients, new fields) only
evaluate the form and run ``np.bincount``. Entries are processed in chunks of ``chunk_size`` to
bound memory. For vector bases (``n_components = dim``) the form is evaluated once per
(test component, trial component) pair with the other components zero, and the result is a
block matrix with node-major DOFs (``dof = node * dim + component``).

Inside a form ``u``/``v`` are :class:`~mlsgalerkin.basis.DiscreteField`: value ``(e,)`` and
``grad`` ``(dim, e)`` for scalars; value ``(dim, e)`` and ``grad`` ``(dim, dim, e)`` for vectors
(``grad[a, b] = ∂u_a/∂x_b``), ``e`` entries. The gradient is the rule's (smoothed for SCNI).

``w`` carries ``w.x`` (``(dim, e)`` coordinates), ``w.h`` (local length scale), ``w.n`` (outward
normals, boundary bases only) and every keyword given to ``assemble``. A keyword value may be a
scalar, an array whose last axis has one value per integration point (``(..., n_points)``), or a
field from ``basis.interpolate(u)`` (value and gradient are both passed on). A nodal DOF vector
must be interpolated first: with nodal integration ``n_points == n_nodes``, so a bare array
would be ambiguous.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.basis import DiscreteField, MeshfreeBasis

__all__ = ["BilinearForm", "LinearForm", "Functional", "FormExtraParams"]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
DEFAULT_CHUNK = 1 << 20


class FormExtraParams(dict):
    """The ``w`` argument of a form: a dict with attribute access (``w.x``, ``w.h``, ``w.f``)."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(
                f"w has no parameter {name!r}; available: {', '.join(sorted(self))}. Pass extra "
                f"data as keywords: form.assemble(basis, {name}=...)"
            ) from None


@dataclass(frozen=True)
class _Pattern:
    """Expanded (point, trial pair, test pair) triples and their CSR slots (cached)."""

    point: NDArray[np.integer]
    trial_pair: NDArray[np.integer]
    test_pair: NDArray[np.integer]
    slot: NDArray[np.integer]
    indptr: NDArray[np.int64]
    indices: NDArray[np.int32]

    @property
    def n_entries(self) -> int:
        return self.point.shape[0]

    @property
    def nnz(self) -> int:
        return self.indices.shape[0]


def _index_dtype(n: int):
    return np.int32 if n < np.iinfo(np.int32).max else np.int64


def _expand(trial: MeshfreeBasis, test: MeshfreeBasis) -> _Pattern:
    """All ``(k, p, q)`` with trial pair ``p`` and test pair ``q`` at the same point ``k``."""
    from scipy.sparse import csr_array

    T, S = trial.table, test.table
    nt, ns = np.diff(T.indptr), np.diff(S.indptr)
    counts = nt * ns
    total = int(counts.sum())
    idt = _index_dtype(max(total, T.n_pairs, S.n_pairs))
    start = np.concatenate(([0], np.cumsum(counts)[:-1]))
    point = np.repeat(np.arange(T.n_points, dtype=idt), counts)
    local = np.arange(total, dtype=np.int64) - np.repeat(start, counts)
    ns_e = ns[point]
    p = (T.indptr[point] + local // ns_e).astype(idt)
    q = (S.indptr[point] + local % ns_e).astype(idt)
    del local, ns_e
    # node-level pattern: (i, j) share a point <=> (S_patternᵀ T_pattern)_ij > 0 (C++ sparse
    # product, much faster than np.unique over the triples); entries find their CSR slot by a
    # binary search in the sorted (row, col) keys
    Sp = csr_array((np.ones(S.n_pairs), S.indices, S.indptr), shape=(S.n_points, S.n_nodes))
    Tp = csr_array((np.ones(T.n_pairs), T.indices, T.indptr), shape=(T.n_points, T.n_nodes))
    P = csr_array(Sp.T @ Tp)
    P.sort_indices()
    n_cols = T.n_nodes
    rows = np.repeat(np.arange(S.n_nodes, dtype=np.int64), np.diff(P.indptr))
    pattern_keys = rows * n_cols + P.indices
    key = S.indices[q].astype(np.int64) * n_cols + T.indices[p]
    slot = np.searchsorted(pattern_keys, key)
    del key
    logger.debug("expanded %d triples into %d nonzeros (%s x %s)", total, P.nnz, test.name,
                 trial.name)
    return _Pattern(point, p, q, slot.astype(_index_dtype(P.nnz)), P.indptr.astype(np.int64),
                    P.indices.astype(np.int32))


def _pattern(trial: MeshfreeBasis, test: MeshfreeBasis) -> _Pattern:
    cached = trial._triples.get(id(test))
    if cached is not None and cached[0] is test:
        return cached[1]
    pat = _expand(trial, test)
    trial._triples[id(test)] = (test, pat)
    return pat


def _check_basis(basis: Any, role: str) -> MeshfreeBasis:
    if not isinstance(basis, MeshfreeBasis):
        raise ValueError(f"{role} must be a MeshfreeBasis, got {type(basis).__name__}")
    return basis


def _check_compatible(trial: MeshfreeBasis, test: MeshfreeBasis) -> None:
    if test is trial:
        return
    if trial.n_points != test.n_points or trial.dim != test.dim:
        raise ValueError(
            f"trial and test bases must share the integration points: {trial.n_points} vs "
            f"{test.n_points} points in {trial.dim}D/{test.dim}D"
        )
    scale = max(1.0, float(np.abs(trial.points).max()))
    if not np.allclose(trial.points, test.points, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("trial and test bases have different integration points")
    if not np.allclose(trial.weights, test.weights, rtol=1e-12, atol=0.0):
        raise ValueError("trial and test bases have different integration weights")


def _point_params(basis: MeshfreeBasis, kwargs: dict[str, Any]) -> dict[str, Any]:
    """Validate per-point parameters (defaults + user keywords)."""
    out: dict[str, Any] = dict(basis.default_parameters())
    n = basis.n_points
    for name, value in kwargs.items():
        if isinstance(value, DiscreteField):
            if value.ndim == 0 or value.shape[-1] != n:
                raise ValueError(f"field {name!r} has shape {value.shape}; expected (..., {n}) "
                                 f"values at the {n} integration points (use basis.interpolate(u))")
            out[name] = value
            continue
        if callable(value):
            raise ValueError(f"keyword {name!r} is a function; evaluate it inside the form, e.g. "
                             f"{name}(w.x), or pass its values at the integration points")
        a = np.asarray(value)
        if a.ndim == 0:
            out[name] = value
        elif a.shape[-1] == n:
            out[name] = a
        else:
            raise ValueError(
                f"keyword {name!r} has shape {a.shape}; expected a scalar or (..., {n}) values at "
                f"the {n} integration points. Interpolate a nodal DOF vector first: "
                f"form.assemble(basis, {name}=basis.interpolate(u))"
            )
    return out


def _take(params: dict[str, Any], k: NDArray[np.integer]) -> FormExtraParams:
    w = FormExtraParams()
    for name, value in params.items():
        if isinstance(value, DiscreteField):
            w[name] = value.take_points(k)
        elif isinstance(value, np.ndarray) and value.ndim > 0:
            w[name] = value[..., k]
        else:
            w[name] = value
    return w


def _component_field(phi: FloatArray, dphi: FloatArray, c: int, n_c: int) -> DiscreteField:
    """Shape function in component ``c`` of an ``n_c``-component field (others zero)."""
    if n_c == 1:
        return DiscreteField(phi, dphi)
    value = np.zeros((n_c,) + phi.shape)
    value[c] = phi
    grad = np.zeros((n_c,) + dphi.shape)
    grad[c] = dphi
    return DiscreteField(value, grad)


def _chunks(n: int, size: int):
    for a in range(0, n, size):
        yield slice(a, min(n, a + size))


class Form:
    """Base class: wraps a plain function; ``Form(chunk_size=...)`` also works as a decorator."""

    def __init__(self, form: Callable | None = None, *, chunk_size: int = DEFAULT_CHUNK) -> None:
        if form is not None and not callable(form):
            raise ValueError(f"{type(self).__name__} wraps a function, got {type(form).__name__}")
        if int(chunk_size) < 1:
            raise ValueError(f"chunk_size must be >= 1, got {chunk_size}")
        self.form = form
        self.chunk_size = int(chunk_size)
        if form is not None:
            functools.update_wrapper(self, form)

    def __call__(self, *args: Any) -> Any:
        if self.form is None:  # used as @BilinearForm(chunk_size=...)
            if len(args) != 1 or not callable(args[0]):
                raise ValueError(
                    f"{type(self).__name__}(...) used as a decorator needs one function"
                )
            return type(self)(args[0], chunk_size=self.chunk_size)
        return self.form(*args)

    @property
    def name(self) -> str:
        return getattr(self.form, "__name__", type(self).__name__)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name})"

    def _evaluate(self, args: tuple, n: int) -> FloatArray:
        val = np.asarray(self.form(*args), dtype=np.float64)
        if val.shape == (n,):
            return val
        try:
            return np.broadcast_to(val, (n,))
        except ValueError:
            raise ValueError(
                f"form {self.name!r} returned shape {val.shape}; it must give one scalar per entry "
                f"({n},): contract vectors/tensors with dot/ddot"
            ) from None


class BilinearForm(Form):
    r"""``a(u, v, w)`` assembled into ``K[i, j] = Σ_k w_k a(N_j, N_i)(x_k)`` (``u`` trial, ``v`` test)."""

    def assemble(self, basis: MeshfreeBasis, test_basis: MeshfreeBasis | None = None,
                 **kwargs: Any):
        """Assemble into a ``scipy.sparse.csr_array`` of shape ``(test n_dofs, trial n_dofs)``.

        Parameters
        ----------
        basis : MeshfreeBasis
            Trial basis (``u``); also the test basis unless ``test_basis`` is given.
        test_basis : MeshfreeBasis, optional
            Test basis (``v``) for Petrov–Galerkin; must share the integration points and
            weights of ``basis`` (its shape functions, nodes and components may differ).
        **kwargs
            Extra data for ``w`` (scalars, per-point arrays, interpolated fields).
        """
        from scipy.sparse import bsr_array, csr_array

        if self.form is None:
            raise ValueError("this BilinearForm wraps no function")
        trial = _check_basis(basis, "basis")
        test = trial if test_basis is None else _check_basis(test_basis, "test_basis")
        _check_compatible(trial, test)
        params = _point_params(trial, kwargs)
        pat = _pattern(trial, test)
        T, S = trial.table, test.table
        ct, cv = trial.n_components, test.n_components
        data = np.zeros((pat.nnz, cv, ct))
        for sl in _chunks(pat.n_entries, self.chunk_size):
            k, p, q, slot = pat.point[sl], pat.trial_pair[sl], pat.test_pair[sl], pat.slot[sl]
            e = k.shape[0]
            w = _take(params, k)
            wk = trial.weights[k]
            phi_u, dphi_u = T.values[p], T.gradients[p].T
            phi_v, dphi_v = S.values[q], S.gradients[q].T
            for b in range(ct):
                u = _component_field(phi_u, dphi_u, b, ct)
                for a in range(cv):
                    v = _component_field(phi_v, dphi_v, a, cv)
                    val = self._evaluate((u, v, w), e)
                    data[:, a, b] += np.bincount(slot, weights=val * wk, minlength=pat.nnz)
        shape = (test.n_dofs, trial.n_dofs)
        if ct == cv == 1:
            return csr_array((data[:, 0, 0], pat.indices, pat.indptr), shape=shape)
        return csr_array(bsr_array((data, pat.indices, pat.indptr), shape=shape))


class LinearForm(Form):
    r"""``l(v, w)`` assembled into ``f[i] = Σ_k w_k l(N_i)(x_k)``."""

    def assemble(self, basis: MeshfreeBasis, **kwargs: Any) -> FloatArray:
        """Assemble into a dense ``(n_dofs,)`` vector (node-major for vector bases)."""
        if self.form is None:
            raise ValueError("this LinearForm wraps no function")
        test = _check_basis(basis, "basis")
        params = _point_params(test, kwargs)
        S = test.table
        cv = test.n_components
        out = np.zeros((test.n_nodes, cv))
        rows = test.pair_points
        for sl in _chunks(S.n_pairs, self.chunk_size):
            k = rows[sl]
            w = _take(params, k)
            wk = test.weights[k]
            nodes = S.indices[sl]
            phi, dphi = S.values[sl], S.gradients[sl].T
            for a in range(cv):
                v = _component_field(phi, dphi, a, cv)
                val = self._evaluate((v, w), k.shape[0])
                out[:, a] += np.bincount(nodes, weights=val * wk, minlength=test.n_nodes)
        return out.reshape(-1)


class Functional(Form):
    r"""``J(w)`` integrated as ``Σ_k w_k J(w)(x_k)`` (a float)."""

    def assemble(self, basis: MeshfreeBasis, **kwargs: Any) -> float:
        if self.form is None:
            raise ValueError("this Functional wraps no function")
        b = _check_basis(basis, "basis")
        w = FormExtraParams(_point_params(b, kwargs))
        val = self._evaluate((w,), b.n_points)
        return float(np.dot(val, b.weights))
