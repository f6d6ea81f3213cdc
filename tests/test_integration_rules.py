"""Nodal integration: Voronoi volumes, SCNI consistency and its integration constraint."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.integration import (
    direct_nodal_integration,
    rectangle,
    stabilized_conforming_nodal_integration,
    voronoi_volumes,
)


def perturbed_grid(n, rng, jitter=0.3):
    dx = 1.0 / (n - 1)
    g = np.stack(np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij"), -1).reshape(-1, 2)
    inner = (g > 1e-9).all(1) & (g < 1 - 1e-9).all(1)
    g[inner] += rng.uniform(-jitter, jitter, (inner.sum(), 2)) * dx
    return g, dx


def test_voronoi_volumes_tile_the_domain(rng):
    g, dx = perturbed_grid(12, rng)
    v = voronoi_volumes(g, rectangle((0, 0), (1, 1)))
    assert (v > 0).all()
    assert v.sum() == pytest.approx(1.0, rel=1e-13)
    lattice, _ = perturbed_grid(5, rng, jitter=0.0)
    v = voronoi_volumes(lattice, rectangle((0, 0), (1, 1)))
    np.testing.assert_allclose(np.sort(v)[-9:], 1 / 16, rtol=1e-12)  # interior cells are squares


def test_voronoi_bad_input():
    with pytest.raises(ValueError, match="counter-clockwise"):
        voronoi_volumes(np.random.default_rng(0).random((5, 2)), rectangle((0, 0), (1, 1))[::-1])
    with pytest.raises(ValueError, match="duplicates"):
        voronoi_volumes(np.array([[0.2, 0.2], [0.2, 0.2], [0.5, 0.7]]), rectangle((0, 0), (1, 1)))


@pytest.mark.parametrize("basis", ["linear", "quadratic"])
def test_scni_smoothed_gradients_are_linearly_consistent(basis, rng):
    g, dx = perturbed_grid(12, rng)
    r = stabilized_conforming_nodal_integration(g, 2.0 * dx, rectangle((0, 0), (1, 1)), basis=basis)
    for k in range(2):
        np.testing.assert_allclose(r.table.gradient(g[:, k]), np.tile(np.eye(2)[k], (len(g), 1)), atol=1e-11)
    np.testing.assert_allclose(r.table.gradient(np.ones(len(g))), 0.0, atol=1e-11)


def test_scni_satisfies_the_integration_constraint_dni_does_not(rng):
    """Σ_L ∇̃N_I(x_L) A_L equals the boundary integral of N_I n for every node I."""
    g, dx = perturbed_grid(12, rng)
    dom = rectangle((0, 0), (1, 1))
    s = stabilized_conforming_nodal_integration(g, 1.5 * dx, dom, n_gauss=3)
    d = direct_nodal_integration(g, 1.5 * dx, s.weights)
    # the same boundary integral computed with SCNI's own cell-edge quadrature: for a node
    # I, Σ_L A_L ∇̃N_I(x_L) telescopes to the boundary edges; interior nodes far from the
    # boundary therefore get exactly zero
    lhs = np.column_stack([m.T @ s.weights for m in s.table.gradient_matrices()])
    far = (np.abs(g - 0.5) < 0.5 - 2 * 1.5 * dx * 1.01).all(axis=1)
    assert far.sum() > 10
    assert np.abs(lhs[far]).max() < 1e-14
    dni = np.column_stack([m.T @ d.weights for m in d.table.gradient_matrices()])
    assert np.abs(dni[far]).max() > 1e-4  # DNI violates it
