"""Galerkin sums: numba = numpy, conservation identities, mass consistency, exact continuity."""

from __future__ import annotations

import numpy as np
import pytest

import mlsgalerkin
from mlsgalerkin import assembly


def particles(dim, rng, n_side=None):
    n_side = n_side or {1: 60, 2: 16, 3: 7}[dim]
    dx = 1.0 / (n_side - 1)
    g = np.stack(np.meshgrid(*[np.linspace(0, 1, n_side)] * dim, indexing="ij"), -1).reshape(-1, dim)
    g = g + rng.uniform(-0.25, 0.25, g.shape) * dx
    table = mlsgalerkin.shape_functions(g, g, 1.4 * dx)
    assert table.n_fallback == 0
    masses = rng.uniform(0.5, 1.5, len(g)) * dx**dim * 1000.0
    rho = rng.uniform(990, 1010, len(g))
    return g, table, masses, rho


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_compiled_scatter_matches_numpy(dim, rng):
    x, table, M, rho = particles(dim, rng)
    V = M / rho
    sig = rng.normal(size=(len(x), dim, dim))
    v = rng.normal(size=(len(x), dim))
    np.testing.assert_allclose(assembly.internal_force(table, sig, V),
                               assembly.internal_force_reference(table, sig, V), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(assembly.lumped_mass(table, M), assembly.lumped_mass_reference(table, M), rtol=1e-13)
    np.testing.assert_allclose(assembly.velocity_gradient(table, v),
                               assembly.velocity_gradient_reference(table, v), rtol=1e-12, atol=1e-10)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_internal_force_conserves_momentum(dim, rng):
    x, table, M, rho = particles(dim, rng)
    V = M / rho
    sig = rng.normal(size=(len(x), dim, dim)) * 1e3
    f = assembly.internal_force(table, sig, V)
    scale = np.abs(f).max()
    assert np.abs(f.sum(axis=0)).max() < 1e-11 * scale * len(x)  # Σ_i f_i = 0, any stress
    sym = 0.5 * (sig + sig.transpose(0, 2, 1))
    f = assembly.internal_force(table, sym, V)
    torque = np.einsum("ia,ib->ab", x, f)  # Σ_i x_i ⊗ f_i must be symmetric
    assert np.abs(torque - torque.T).max() < 1e-10 * np.abs(f).max() * len(x)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_mass_consistency(dim, rng):
    x, table, M, rho = particles(dim, rng)
    m = assembly.lumped_mass(table, M)
    assert m.sum() == pytest.approx(M.sum(), rel=1e-13)
    C = assembly.consistent_mass(table, M)
    np.testing.assert_allclose(C.sum(axis=1), m, rtol=1e-12)
    assert abs(C - C.T).max() < 1e-14 * abs(C).max()


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_continuity_rate_exact_for_linear_velocity(dim, rng):
    x, table, M, rho = particles(dim, rng)
    A = rng.normal(size=(dim, dim))
    v = x @ A.T + rng.normal(size=dim)  # v = A x + c, ∇v = A
    L = assembly.velocity_gradient(table, v)
    np.testing.assert_allclose(L, np.broadcast_to(A, L.shape), atol=1e-10)
    np.testing.assert_allclose(assembly.continuity_rate(table, v, rho), -rho * np.trace(A), rtol=1e-10)


def test_body_force_total_and_bad_shapes(rng):
    x, table, M, rho = particles(2, rng)
    V = M / rho
    g = np.array([0.0, -9.81])
    f = assembly.body_force(table, rho[:, None] * g, V)
    np.testing.assert_allclose(f.sum(axis=0), M.sum() * g, rtol=1e-12)
    with pytest.raises(ValueError, match=r"stress must have shape"):
        assembly.internal_force(table, np.zeros((len(x), 3, 3)), V)
    with pytest.raises(ValueError, match="not finite at integration point 3"):
        bad = V.copy()
        bad[3] = np.nan
        assembly.internal_force(table, np.zeros((len(x), 2, 2)), bad)
