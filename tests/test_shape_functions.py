"""Shape functions: reproduction, partition of unity, exact gradients, fast/general/numpy
agreement, the fallback policy and the hard cases.

Round-off tolerances scale with the conditioning that is actually present: a reproduction
error of ``eps * cond(M) * |u| / h`` (gradients) is round-off, anything larger is a bug.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mlsgalerkin
from mlsgalerkin.approximation import ShapeFunctionFallbackError, ShapeFunctionFallbackWarning
from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.approximation.reference import reference_shape_functions
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.polynomials import evaluate_basis_numpy, monomial_exponents

EPS = np.finfo(float).eps
ORDERS = {"constant": 0, "linear": 1, "quadratic": 2}


def lattice(dim: int, n_side: int, jitter: float, rng) -> np.ndarray:
    axes = [np.arange(n_side, dtype=float) / (n_side - 1)] * dim
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, dim)
    return g + rng.uniform(-jitter, jitter, g.shape) / (n_side - 1)


def cloud(kind: str, dim: int, rng) -> tuple[np.ndarray, float]:
    """Nodes on the unit cube and their nominal spacing."""
    n_side = {1: 41, 2: 13, 3: 7}[dim]
    dx = 1.0 / (n_side - 1)
    if kind == "jittered":
        return lattice(dim, n_side, 0.3, rng), dx
    return rng.random((n_side**dim, dim)), dx


def polynomial(order: int, dim: int, rng):
    """A random complete polynomial of ``order``: values and gradients at given points."""
    exps = monomial_exponents(dim, order)
    coef = rng.normal(size=exps.shape[0])
    shift = rng.normal(size=dim) * 0.1

    def value(x):
        return evaluate_basis_numpy(x - shift, order) @ coef

    def grad(x):
        g = np.zeros((x.shape[0], dim))
        for a, e in enumerate(exps):
            for k in range(dim):
                if e[k] == 0:
                    continue
                de = e.copy()
                de[k] -= 1
                g[:, k] += coef[a] * e[k] * np.prod((x - shift) ** de, axis=1)
        return g

    return value, grad


def assert_reproduces(table, nodes, order, rng, h):
    """Complete polynomials of ``order`` reproduced at every point that kept ``order``."""
    kept = table.order >= order
    assert kept.any()
    value, grad = polynomial(order, nodes.shape[1], rng)
    u = value(nodes)
    scale = np.abs(u).max() + 1.0
    cond = table.condition[kept].max()
    tol_v = 200 * EPS * cond * scale
    tol_g = 200 * EPS * cond * scale / np.min(h)
    err_v = np.abs(table.interpolate(u) - value(table.points))[kept].max()
    err_g = np.abs(table.gradient(u) - grad(table.points))[kept].max()
    assert err_v <= tol_v, (err_v, tol_v, cond)
    assert err_g <= tol_g, (err_g, tol_g, cond)


def build(points, nodes, h, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShapeFunctionFallbackWarning)
        return mlsgalerkin.shape_functions(points, nodes, h, **kw)


# --------------------------------------------------------------------------------------
# reproduction, partition of unity, gradient identities
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("kind", ["jittered", "random"])
@pytest.mark.parametrize("basis", ["constant", "linear", "quadratic"])
@pytest.mark.parametrize("method", ["mls", "rkpm", "orthogonal"])
def test_reproduction_and_partition_of_unity(dim, kind, basis, method, rng):
    nodes, dx = cloud(kind, dim, rng)
    order = ORDERS[basis]
    h = np.full(len(nodes), (1.3 + 0.5 * order) * dx * (1.5 if kind == "random" else 1.0))
    volumes = rng.uniform(0.5, 1.5, len(nodes)) * dx**dim if method == "rkpm" else None
    points = np.vstack([nodes[:20], rng.random((40, dim))])
    table = build(points, nodes, h, basis=basis, method=method, volumes=volumes)
    assert np.isfinite(table.values).all() and np.isfinite(table.gradients).all()
    # partition of unity and Σ ∇N = 0 hold at every point (all orders >= 0)
    ones = np.ones(len(nodes))
    cond = table.condition.max()
    assert np.abs(table.interpolate(ones) - 1).max() < 200 * EPS * cond
    assert np.abs(table.gradient(ones)).max() < 200 * EPS * cond / h.min()
    assert_reproduces(table, nodes, order, rng, h)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_linear_basis_gradient_identity(dim, rng):
    """Σ_j x_j ⊗ ∇N_j = I for a linear basis (the angular-momentum identity)."""
    nodes, dx = cloud("jittered", dim, rng)
    table = build(nodes, nodes, 1.4 * dx)
    assert table.n_fallback == 0
    for k in range(dim):
        np.testing.assert_allclose(table.gradient(nodes[:, k]), np.eye(dim)[k].repeat(len(nodes)).reshape(dim, -1).T,
                                   atol=1e-10)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("basis", ["linear", "quadratic"])
def test_orthogonal_equals_mls(dim, basis, rng):
    nodes, dx = cloud("random", dim, rng)
    h = (2.0 + ORDERS[basis]) * dx
    a = build(nodes, nodes, h, basis=basis, method="mls")
    b = build(nodes, nodes, h, basis=basis, method="orthogonal")
    both = a.order == b.order
    assert both.mean() > 0.95
    sel = np.repeat(both, a.n_neighbors)
    tol = 1e-13 * a.condition.max()
    np.testing.assert_allclose(b.values[sel], a.values[sel], atol=tol)
    np.testing.assert_allclose(b.gradients[sel], a.gradients[sel], atol=tol / dx)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("basis", ["constant", "linear", "quadratic"])
def test_gradients_match_central_differences(dim, basis, rng):
    nodes, dx = cloud("jittered", dim, rng)
    h = (1.5 + 0.5 * ORDERS[basis]) * dx
    points = 0.2 + 0.6 * rng.random((15, dim))
    table = build(points, nodes, h, basis=basis, kernel="quintic_spline")
    G = [g.toarray() for g in table.gradient_matrices()]
    step = 1e-6 * dx
    for k in range(dim):
        e = np.zeros(dim)
        e[k] = step
        up = build(points + e, nodes, h, basis=basis, kernel="quintic_spline").value_matrix().toarray()
        dn = build(points - e, nodes, h, basis=basis, kernel="quintic_spline").value_matrix().toarray()
        fd = (up - dn) / (2 * step)
        np.testing.assert_allclose(G[k], fd, atol=2e-6 * np.abs(G[k]).max())


# --------------------------------------------------------------------------------------
# implementations agree: numba general, numba fused 2D, numpy reference
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("order", [0, 1, 2])
def test_compiled_matches_numpy_reference(dim, order, rng):
    nodes, dx = cloud("random", dim, rng)
    h = rng.uniform(1.8, 2.6, len(nodes)) * dx * (1 + 0.5 * order)
    points = rng.random((30, dim))
    vol = rng.uniform(0.5, 2.0, len(nodes))
    kern = get_kernel("wendland_c2")
    nb = find_neighbors(points, nodes, node_radius=kern.support * h)
    nodes_c = np.ascontiguousarray(nodes)
    for volumes, method in ((None, "mls"), (vol, "rkpm")):
        fast = evaluate_shape_functions(points, nodes_c, h, nb, kern, order, method, volumes)
        v, g, used = reference_shape_functions(points, nodes_c, h, nb, kern, order, volumes)
        np.testing.assert_array_equal(fast.order, used)
        np.testing.assert_allclose(fast.values, v, atol=1e-12 * fast.condition.max())
        np.testing.assert_allclose(fast.gradients, g, atol=1e-12 * fast.condition.max() / dx)


@pytest.mark.parametrize("kind", ["jittered", "random"])
@pytest.mark.parametrize("method", ["mls", "rkpm"])
def test_fused_2d_linear_matches_general_path(kind, method, rng):
    nodes, dx = cloud(kind, 2, rng)
    nodes = np.vstack([nodes, [[2.0, 2.0], [2.0 + 0.5 * dx, 2.0]]])  # two lonely nodes: fallback
    h = np.full(len(nodes), 1.3 * dx)
    vol = rng.uniform(0.5, 2.0, len(nodes)) if method == "rkpm" else None
    kern = get_kernel("cubic_spline")
    nb = find_neighbors(nodes, nodes, node_radius=kern.support * h)
    a = evaluate_shape_functions(nodes, nodes, h, nb, kern, 1, method, vol, fast=True)
    b = evaluate_shape_functions(nodes, nodes, h, nb, kern, 1, method, vol, fast=False)
    np.testing.assert_array_equal(a.order, b.order)
    assert a.n_fallback >= 2
    np.testing.assert_allclose(a.condition, b.condition, rtol=1e-8)
    np.testing.assert_allclose(a.values, b.values, atol=1e-11 * a.condition.max())
    np.testing.assert_allclose(a.gradients, b.gradients, atol=1e-11 * a.condition.max() / dx)


# --------------------------------------------------------------------------------------
# robustness: fallbacks and hard cases (no NaN, fallback reported, reproduction where kept)
# --------------------------------------------------------------------------------------


def _check_hard_case(points, nodes, h, order, rng, expect_fallback):
    basis = {0: "constant", 1: "linear", 2: "quadratic"}[order]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = mlsgalerkin.shape_functions(points, nodes, h, basis=basis)
    assert np.isfinite(table.values).all() and np.isfinite(table.gradients).all()
    assert np.isfinite(table.condition).all()
    reported = any(issubclass(w.category, ShapeFunctionFallbackWarning) for w in caught)
    assert reported == (table.n_fallback > 0)
    if expect_fallback:
        assert table.n_fallback > 0
    ones = np.ones(len(nodes))
    assert np.abs(table.interpolate(ones) - 1).max() < 1e-12
    if (table.order >= order).any() and order > 0:
        assert_reproduces(table, nodes, order, rng, np.broadcast_to(h, (len(nodes),)))
    return table


@pytest.mark.parametrize("order", [1, 2])
def test_domain_edges_and_corners(order, rng):
    nodes, dx = cloud("jittered", 2, rng)
    corners = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0], [0, 0.5]], dtype=float)
    corners = np.vstack([corners, corners + [[-0.5 * dx, -0.5 * dx]]])  # just outside the cloud
    _check_hard_case(corners, nodes, (1.3 + 0.5 * order) * dx, order, rng, expect_fallback=False)


def test_nearly_collinear_nodes_fall_back(rng):
    x = np.linspace(0.0, 1.0, 30)
    nodes = np.column_stack([x, 1e-11 * rng.standard_normal(30)])
    table = _check_hard_case(nodes, nodes, 0.08, 1, rng, expect_fallback=True)
    assert (table.order[table.fallback] == 0).all()


@pytest.mark.parametrize("order", [1, 2])
def test_coordinates_offset_by_1e6(order, rng):
    nodes, dx = cloud("jittered", 2, rng)
    h = (1.3 + 0.5 * order) * dx
    base = build(nodes, nodes, h, basis=list(ORDERS)[order])
    shifted = _check_hard_case(nodes + 1e6, nodes + 1e6, h, order, rng, expect_fallback=False)
    np.testing.assert_allclose(shifted.values, base.values, atol=1e-8)


@pytest.mark.parametrize("order", [1, 2])
def test_spacing_1e_minus_6(order, rng):
    nodes, dx = cloud("random", 3, rng)
    nodes, dx = nodes * 1e-6, dx * 1e-6
    _check_hard_case(nodes, nodes, (2.0 + 0.5 * order) * dx, order, rng, expect_fallback=False)


def test_clustered_nodes_1000_to_1(rng):
    coarse = lattice(2, 11, 0.2, rng)  # spacing 0.1
    fine = 0.5 + lattice(2, 11, 0.2, rng) * 1e-3  # spacing 1e-4 around (0.5, 0.5)
    nodes = np.vstack([coarse, fine])
    h = np.concatenate([np.full(len(coarse), 0.14), np.full(len(fine), 1.4e-4)])
    table = _check_hard_case(nodes, nodes, h, 1, rng, expect_fallback=False)
    assert table.n_neighbors.max() > 5 * table.n_neighbors.min()


def test_single_neighbour_point_falls_back_to_shepard(rng):
    nodes, dx = cloud("jittered", 2, rng)
    nodes = np.vstack([nodes, [[3.0, 3.0]]])
    table = _check_hard_case(np.array([[3.0 + 0.1 * dx, 3.0]]), nodes, 1.3 * dx, 1, rng, expect_fallback=True)
    assert table.n_neighbors[0] == 1 and table.order[0] == 0
    assert table.values[0] == pytest.approx(1.0)
    np.testing.assert_array_equal(table.gradients[0], 0.0)


def test_fallback_modes(rng):
    nodes = np.column_stack([np.linspace(0, 1, 20), np.zeros(20)])  # exactly collinear
    with pytest.warns(ShapeFunctionFallbackWarning, match="fell back"):
        mlsgalerkin.shape_functions(nodes, nodes, 0.1)
    with pytest.raises(ShapeFunctionFallbackError, match="fell back"):
        mlsgalerkin.shape_functions(nodes, nodes, 0.1, on_fallback="raise")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t = mlsgalerkin.shape_functions(nodes, nodes, 0.1, on_fallback="ignore")
    assert t.n_fallback == 20 and t.diagnostics()["points_per_order"] == {0: 20}


def test_quadratic_falls_back_to_linear_before_shepard(rng):
    """A 2D cross of nodes supports a linear fit but not a quadratic one (no ξ₁ξ₂ term)."""
    t = np.linspace(-1, 1, 21)
    nodes = np.vstack([np.column_stack([t, 0 * t]), np.column_stack([0 * t[t != 0], t[t != 0]])])
    table = build(np.array([[0.0, 0.0]]), nodes, 0.6, basis="quadratic")
    assert table.order[0] == 1


# --------------------------------------------------------------------------------------
# Shepard, singular Shepard and input errors
# --------------------------------------------------------------------------------------


def test_shepard_bounds_and_linear_failure(rng):
    nodes, dx = cloud("random", 2, rng)
    t = build(nodes, nodes, 2 * dx, method="shepard")
    assert (t.values >= 0).all() and (t.values <= 1).all()
    assert np.abs(t.interpolate(np.ones(len(nodes))) - 1).max() < 1e-14
    assert np.abs(t.interpolate(nodes[:, 0]) - nodes[:, 0]).max() > 1e-4  # zeroth order only


def test_singular_shepard_interpolates(rng):
    nodes, dx = cloud("random", 2, rng)
    t = build(nodes, nodes, 2 * dx, method="singular_shepard")
    u = rng.normal(size=len(nodes))
    np.testing.assert_allclose(t.interpolate(u), u, atol=1e-14)  # Kronecker delta
    np.testing.assert_array_equal(t.gradients, 0.0)  # flat spots at the nodes
    pts = rng.random((50, 2))
    s = build(pts, nodes, 2 * dx, method="singular_shepard")
    assert np.abs(s.interpolate(np.ones(len(nodes))) - 1).max() < 1e-14
    assert (s.values >= 0).all() and (s.values <= 1).all()
    np.testing.assert_allclose(s.gradient(np.ones(len(nodes))), 0.0, atol=1e-9)


def test_point_without_neighbours_raises_with_its_index():
    nodes = np.random.default_rng(0).random((50, 2))
    pts = np.array([[0.5, 0.5], [9.0, 9.0]])
    with pytest.raises(ValueError, match=r"no node within the support, first point 1 at \[9.0, 9.0\]"):
        mlsgalerkin.shape_functions(pts, nodes, 0.2)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"kernel": "super_gaussian"}, "negative values"),
        ({"kernel": "new_quartic"}, "negative values"),
        ({"kernel": "nope"}, "unknown kernel"),
        ({"method": "rkpm"}, "pass volumes"),
        ({"method": "mls", "volumes": np.ones(50)}, "does not use volumes"),
        ({"method": "magic"}, "unknown method"),
        ({"basis": "cubic"}, "unknown basis"),
        ({"method": "shepard", "basis": "linear"}, "zeroth order"),
        ({"h": -1.0}, "h must be positive"),
        ({"h": np.ones(3)}, "one value per node"),
        ({"volumes": np.zeros(50), "method": "rkpm"}, "volumes must be positive"),
        ({"on_fallback": "shout"}, "on_fallback"),
    ],
)
def test_bad_input_is_reported_clearly(kwargs, match):
    nodes = np.random.default_rng(0).random((50, 2))
    args = {"h": 0.2, **kwargs}
    with pytest.raises(ValueError, match=match):
        mlsgalerkin.shape_functions(nodes, nodes, **args)


def test_interpolate_shapes_and_errors(rng):
    nodes, dx = cloud("jittered", 2, rng)
    t = build(nodes[:10], nodes, 1.5 * dx)
    assert t.interpolate(np.ones(len(nodes))).shape == (10,)
    assert t.interpolate(np.ones((len(nodes), 3))).shape == (10, 3)
    assert t.gradient(np.ones(len(nodes))).shape == (10, 2)
    assert t.gradient(np.ones((len(nodes), 3))).shape == (10, 3, 2)
    with pytest.raises(ValueError, match="nodal values must have shape"):
        t.interpolate(np.ones(len(nodes) + 1))


@pytest.mark.parametrize("kernel", ["cubic_spline", "wendland_c2", "quintic_spline"])
@pytest.mark.parametrize("fast", [True, False])
def test_rank_deficient_neighbourhoods_never_keep_linear_order(kernel, fast):
    """One or two neighbours cannot support a 2D linear fit, whatever the rounding.

    Regression: the fused 2D path once accepted ~10 % of such points, because the adjugate and
    the determinant of a rank-deficient 3x3 matrix are both rounding noise and their ratio looks
    like a well-conditioned inverse.
    """
    rng = np.random.default_rng(7)
    k = get_kernel(kernel)
    for _ in range(200):
        n = int(rng.integers(1, 3))
        nodes = rng.random((n, 2))
        pts = nodes[:1] + rng.normal(size=(1, 2)) * 0.05
        h = np.full(n, 0.1)
        nb = find_neighbors(pts, nodes, node_radius=k.support * h)
        if nb.n_pairs == 0:
            continue
        t = evaluate_shape_functions(pts, nodes, h, nb, k, 1, fast=fast)
        assert t.order[0] == 0
        assert np.isfinite(t.gradients).all()


def test_reused_buffers_give_identical_tables(rng):
    """``out=`` reuses an earlier table's pair buffers; results equal a fresh evaluation."""
    nodes, dx = cloud("jittered", 2, rng)
    h = np.full(len(nodes), 1.3 * dx)
    kern = get_kernel("cubic_spline")
    nb = find_neighbors(nodes, nodes, node_radius=kern.support * h)
    first = evaluate_shape_functions(nodes, nodes, h, nb, kern, 1)
    moved = nodes + rng.uniform(-0.05, 0.05, nodes.shape) * dx
    nb2 = find_neighbors(moved, moved, node_radius=kern.support * h)
    fresh = evaluate_shape_functions(moved, moved, h, nb2, kern, 1)
    reused = evaluate_shape_functions(moved, moved, h, nb2, kern, 1, out=first)
    assert np.shares_memory(reused.values, first.values) or nb2.n_pairs > first.values.shape[0]
    np.testing.assert_array_equal(reused.values, fresh.values)
    np.testing.assert_array_equal(reused.gradients, fresh.gradients)


@pytest.mark.parametrize(("dim", "order", "method", "fast", "periodic"), [
    (2, 1, "mls", True, False), (2, 1, "rkpm", True, False), (2, 1, "mls", True, True),
    (2, 2, "mls", False, False), (3, 1, "rkpm", False, True), (2, 1, "orthogonal", False, False)])
def test_kernel_sum_is_the_shepard_sum_of_the_given_volumes(dim, order, method, fast, periodic):
    # table.kernel_sum = Σ_j W(x_i − x_j, h_j) V_j and its gradient, from the shape-function pass
    from mlsgalerkin.periodic import minimum_image
    rng = np.random.default_rng(11)
    side, dx = 1.0, 0.125 if dim == 2 else 1.0 / 6
    g = np.arange(0.0, side, dx)
    nodes = np.stack(np.meshgrid(*([g] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    nodes += rng.uniform(-0.2, 0.2, nodes.shape) * dx
    if periodic:
        nodes %= side
    h = np.full(nodes.shape[0], 1.3 * dx) * rng.uniform(0.95, 1.05, nodes.shape[0])
    V = dx**dim * rng.uniform(0.9, 1.1, nodes.shape[0])
    period = np.array([side] * dim + [0.0] * (3 - dim)) if periodic else None
    k = get_kernel("cubic_spline")
    radius = 2.0 * h.max()
    nb = find_neighbors(nodes, nodes, radius=radius, period=period, lower=np.zeros(dim)) if periodic \
        else find_neighbors(nodes, nodes, radius=radius)
    t = evaluate_shape_functions(nodes, nodes, h, nb, k, order, method, V if method == "rkpm" else None,
                                 fast=fast, period=period, kernel_sum_volumes=V)
    rows = np.repeat(np.arange(nodes.shape[0]), np.diff(nb.indptr))
    j = nb.indices.astype(np.int64)
    d = minimum_image(nodes[rows] - nodes[j], period if periodic else np.zeros(3))   # x_i − x_j
    r = np.sqrt(np.einsum("pd,pd->p", d, d))
    c = np.bincount(rows, k.value(r, h[j], dim) * V[j], minlength=nodes.shape[0])
    dwr = np.where(r > 0, k.derivative(r, h[j], dim) / np.where(r > 0, r, 1.0), 0.0) * V[j]
    grad = np.stack([np.bincount(rows, dwr * d[:, a], minlength=nodes.shape[0]) for a in range(dim)], axis=1)
    np.testing.assert_allclose(t.kernel_sum, c, rtol=1e-12)
    if periodic:
        assert 0.9 < np.median(c) < 1.1          # no boundary anywhere
    else:
        assert c.min() < 0.6 and c.max() > 0.9   # corners, edges and an interior
    np.testing.assert_allclose(t.kernel_sum_gradient, grad, rtol=0, atol=1e-11 * np.abs(grad).max() + 1e-12)
    plain = evaluate_shape_functions(nodes, nodes, h, nb, k, order, method, V if method == "rkpm" else None,
                                     fast=fast, period=period)
    assert plain.kernel_sum is None and np.array_equal(plain.values, t.values)   # asked for, or nothing
