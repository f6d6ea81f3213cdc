"""Implicit second derivatives (quadratic least-squares fit): exact on quadratics, compiled
kernel equal to the numpy reference, clear refusals."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.approximation.implicit_derivatives import (
    implicit_second_derivatives,
    implicit_second_derivatives_reference,
)
from mlsgalerkin.neighbors import find_neighbors


def jittered_lattice(dim: int, n: int, dx: float, jitter: float, seed: int) -> np.ndarray:
    """``n`` points per axis at spacing ``dx``, each moved by up to ``± jitter dx`` per axis."""
    grid = np.stack(np.meshgrid(*[np.arange(n) * dx] * dim, indexing="ij"), axis=-1).reshape(-1, dim)
    return grid + np.random.default_rng(seed).uniform(-jitter, jitter, grid.shape) * dx


def cloud(dim: int, jitter: float = 0.25, seed: int = 0):
    n = {1: 30, 2: 14, 3: 7}[dim]
    dx = 0.01
    x = jittered_lattice(dim, n, dx, jitter, seed)
    h = np.full(x.shape[0], 1.3 * dx)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    return x, h, nb


def quadratic(x: np.ndarray, c0: float, g: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """``f = c0 + g·x + ½ xᵀ Q x`` (its Hessian is ``Q``, symmetric)."""
    return c0 + x @ g + 0.5 * np.einsum("pa,ab,pb->p", x, Q, x)


def apply(H: np.ndarray, nb, f: np.ndarray) -> np.ndarray:
    """``Σ_j H[p(k, j)] f_j`` per point ``(n_points, dim, dim)``."""
    rows = np.repeat(np.arange(nb.n_points), np.diff(nb.indptr))
    out = np.zeros((nb.n_points,) + H.shape[1:])
    np.add.at(out, rows, H * f[nb.indices][:, None, None])
    return out


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_exact_for_quadratics(dim):
    x, h, nb = cloud(dim)
    rng = np.random.default_rng(dim)
    A = rng.normal(size=(dim, dim))
    Q = A + A.T
    H, ok = implicit_second_derivatives(x, x, h, nb)
    assert ok.mean() > 0.9                          # a corner may lack a quadratic's support
    got = apply(H, nb, quadratic(x, 0.7, rng.normal(size=dim), Q))
    assert np.abs(got[ok] - Q).max() < 1e-8 * np.abs(Q).max()
    assert np.array_equal(H, H.transpose(0, 2, 1))
    assert np.all(H[~ok[np.repeat(np.arange(nb.n_points), np.diff(nb.indptr))]] == 0.0)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_compiled_matches_numpy_reference(dim):
    x, h, nb = cloud(dim, seed=3)
    H, ok = implicit_second_derivatives(x, x, h, nb, "wendland_c2")
    Hr, okr = implicit_second_derivatives_reference(x, x, h, nb, "wendland_c2")
    assert np.array_equal(ok, okr)
    assert np.allclose(H, Hr, rtol=1e-9, atol=1e-9 * np.abs(Hr).max())


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**16), jitter=st.floats(0.0, 0.4),
       coef=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3))
def test_any_quadratic_on_any_disorder_2d(seed, jitter, coef):
    x, h, nb = cloud(2, jitter, seed)
    Q = np.array([[coef[0], coef[1]], [coef[1], coef[2]]])
    H, ok = implicit_second_derivatives(x, x, h, nb)
    got = apply(H, nb, quadratic(x, 1.0, np.array([2.0, -3.0]), Q))
    assert np.abs(got[ok] - Q).max() <= 1e-7 * max(1.0, np.abs(Q).max())


def test_sees_the_pairing_mode_the_divergence_misses():
    """Neighbouring columns moving apart and together (velocity ``±1`` alternating along x) has
    no mean divergence, but its second derivatives are of order ``1/Δx²`` (what a stabilisation of
    nodal integration reads)."""
    x, h, nb = cloud(2, jitter=0.0)
    dx = 0.01
    H, ok = implicit_second_derivatives(x, x, h, nb)
    u = (-1.0) ** np.round(x[:, 0] / dx)
    grad_div_x = apply(H, nb, u)[:, 0, 0]            # ∂x(∂x u) of v = (u, 0)
    assert np.median(np.abs(grad_div_x[ok])) * dx**2 > 0.5


def test_too_few_neighbours_give_zero_rows():
    x = np.array([[0.0, 0.0], [0.01, 0.0], [0.0, 0.01], [0.01, 0.01]])
    h = np.full(4, 0.013)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    H, ok = implicit_second_derivatives(x, x, h, nb)      # 4 nodes cannot fix 6 coefficients
    assert not ok.any() and np.all(H == 0.0)


def test_collinear_nodes_give_zero_rows():
    x = np.stack([np.arange(12) * 0.01, np.zeros(12)], axis=1)
    h = np.full(12, 0.013)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    _, ok = implicit_second_derivatives(x, x, h, nb)
    assert not ok.any()


def test_periodic_seam_row_equals_an_interior_row():
    """On a periodic lattice the table is translation invariant: a point on the seam gets the
    same weights as one in the middle."""
    dx, n = 0.01, 12
    x = jittered_lattice(2, n, dx, 0.0, 0)
    h = np.full(x.shape[0], 1.3 * dx)
    period = (n * dx, n * dx)
    nb = find_neighbors(x, x, node_radius=2.0 * h, period=period)
    H, ok = implicit_second_derivatives(x, x, h, nb, period=period)
    assert ok.all()
    f = np.cos(2 * np.pi * x[:, 0] / (n * dx))
    hess = apply(H, nb, f)[:, 0, 0]
    seam, middle = 0, (n // 2) * n                    # the points (0, 0) and (6 dx, 0)
    assert hess[seam] == pytest.approx(-hess[middle], rel=1e-9)   # cos(0) = −cos(π)
    k2 = (2 * np.pi / (n * dx)) ** 2
    assert hess[seam] == pytest.approx(-k2, rel=0.1)


def test_bad_input_is_refused():
    x, h, nb = cloud(2)
    with pytest.raises(ValueError, match="negative values"):
        implicit_second_derivatives(x, x, h, nb, "super_gaussian")
    with pytest.raises(ValueError, match="condition_limit"):
        implicit_second_derivatives(x, x, h, nb, condition_limit=0.5)
    with pytest.raises(ValueError, match="neighbors table"):
        implicit_second_derivatives(x[:-1], x, h, nb)
    with pytest.raises(ValueError, match="h must be positive"):
        implicit_second_derivatives(x, x, -h, nb)
