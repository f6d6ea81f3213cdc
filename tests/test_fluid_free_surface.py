"""Free-surface detection: circle coverage (2D) and the cheap count + asymmetry screen."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.fluid.free_surface import (
    detect_circle_coverage,
    detect_circle_coverage_reference,
    detect_free_surface,
    detect_neighbour_deficit,
    surface_indicators,
    surface_indicators_reference,
)
from mlsgalerkin.neighbors import NeighborTable, find_neighbors
from verification.free_surface_comparison import (
    free_surface_method_comparison,
    hexagonal_block,
    lattice_block,
    ring_disc,
)

METHODS = ("circle", "cheap")


def _table(x, radius=2.2):
    return find_neighbors(x, x, radius=radius)


def _block(n_side, spacing=1.0, hole=0):
    x, exact = lattice_block(n_side, hole)
    return x * spacing, exact


# --------------------------------------------------------------------------------------
# exact answers on the test geometries
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("spacing", [1.0, 0.013])
def test_lattice_block_outer_ring_exactly(method, spacing):
    x, exact = _block(12, spacing)
    surface = detect_free_surface(x, _table(x, 2.2 * spacing), spacing, method=method)
    ij = np.rint(x / spacing).astype(int)
    ring = (ij == 0).any(axis=1) | (ij == 11).any(axis=1)
    assert np.array_equal(exact, ring)
    assert np.array_equal(surface, ring)


@pytest.mark.parametrize("method", METHODS)
def test_larger_search_radius_changes_nothing(method):
    # only neighbours within 2 r (or R_c) matter: a kernel-sized table gives the same flags
    x, exact = _block(15)
    assert np.array_equal(detect_free_surface(x, _table(x, 3.3), 1.0, method=method), exact)


@pytest.mark.parametrize("method", METHODS)
def test_disc_of_rings_outer_ring(method):
    x, exact = ring_disc(8)
    assert np.array_equal(detect_free_surface(x, _table(x), 1.0, method=method), exact)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("hole", [2, 4, 5])
def test_cavity_edge_rows_are_surface(method, hole):
    x, exact = _block(16, hole=hole)
    assert exact.sum() == 4 * 15 + 4 * hole  # outer ring + the four edge rows of the cavity
    assert np.array_equal(detect_free_surface(x, _table(x), 1.0, method=method), exact)


def test_single_vacancy_is_not_a_surface_for_the_circle_test():
    # particles 2 r0 apart across a vacancy: their circles bridge it at r = 1.05 r0
    x, exact = _block(9)
    x = np.delete(x, 40, axis=0)  # the centre (4, 4)
    flags = detect_circle_coverage(x, _table(x), 1.0)
    ij = np.rint(x).astype(int)
    assert np.array_equal(flags, (ij == 0).any(axis=1) | (ij == 8).any(axis=1))


@pytest.mark.parametrize("method", METHODS)
def test_jittered_block(method):
    rng = np.random.default_rng(4)
    x, exact = _block(30)
    x = x + rng.uniform(-0.1, 0.1, x.shape)
    assert np.array_equal(detect_free_surface(x, _table(x), 1.0, method=method), exact)


def test_circle_radius_geometry():
    # square lattice: interior coverage needs r > r0 / sqrt(2); below, every particle is surface
    x, exact = _block(10)
    table = _table(x, 2.2)
    assert detect_circle_coverage(x, table, 1.0, radius_factor=0.69).all()
    assert np.array_equal(detect_circle_coverage(x, table, 1.0, radius_factor=0.72), exact)
    assert np.array_equal(detect_circle_coverage(x, table, 1.0, radius_factor=1.05), exact)


def test_hexagonal_zigzag_recess():
    # recessed particles of a zigzag edge are covered for r > r0, flagged for r <= r0
    x, exact = hexagonal_block(12)
    table = _table(x)
    wide = detect_circle_coverage(x, table, 1.0)
    narrow = detect_circle_coverage(x, table, 1.0, radius_factor=0.95)
    assert not (wide & ~exact).any() and (exact & ~wide).sum() == 2 * (12 // 2 - 1)
    assert np.array_equal(narrow, exact)
    assert np.array_equal(detect_neighbour_deficit(x, table, 1.0), exact)


@pytest.mark.parametrize("method", METHODS)
def test_isolated_and_pair_particles_are_surface(method):
    x, _ = _block(10)
    x = np.vstack([x, [[30.0, 30.0]], [[50.0, 50.0], [51.0, 50.0]]])
    flags = detect_free_surface(x, _table(x), 1.0, method=method)
    assert flags[-3:].all()


def test_cheap_method_three_dimensions():
    g = np.arange(7.0)
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    exact = ((x == 0) | (x == 6)).any(axis=1)
    flags = detect_neighbour_deficit(x, _table(x), 1.0)
    assert np.array_equal(flags, exact)
    with pytest.raises(ValueError, match="two-dimensional"):
        detect_circle_coverage(x, _table(x), 1.0)


def test_cheap_method_one_dimension():
    x = np.arange(20.0)[:, None]
    flags = detect_free_surface(x, _table(x), 1.0, method="cheap")
    assert flags[[0, -1]].all() and not flags[1:-1].any()


def test_n_reference_small_block():
    x, exact = _block(5)
    table = _table(x)
    assert np.array_equal(detect_neighbour_deficit(x, table, 1.0), exact)
    assert np.array_equal(detect_neighbour_deficit(x, table, 1.0, n_reference=12), exact)


# --------------------------------------------------------------------------------------
# compiled vs reference
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_circle_numba_matches_reference_on_random_clouds(seed):
    rng = np.random.default_rng(seed)
    n = 400
    x = rng.random((n, 2)) * np.sqrt(n) * (0.8 + 0.1 * seed)  # densities around 1 per r0^2
    table = _table(x, 2.4)
    for rf, nt in [(1.05, 360), (0.9, 97), (1.3, 360)]:
        a = detect_circle_coverage(x, table, 1.0, radius_factor=rf, n_test_points=nt)
        b = detect_circle_coverage_reference(x, table, 1.0, radius_factor=rf, n_test_points=nt)
        assert np.array_equal(a, b)
        assert 0 < a.sum() < n  # a meaningful mix


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_indicators_numba_matches_reference(dim, rng):
    n = 300
    x = rng.random((n, dim)) * n ** (1.0 / dim)
    table = _table(x, 2.5)
    c1, s1 = surface_indicators(x, table, 1.0)
    c2, s2 = surface_indicators_reference(x, table, 1.0)
    assert np.array_equal(c1, c2)
    np.testing.assert_allclose(s1, s2, rtol=1e-12, atol=1e-14)
    assert ((s1 >= 0) & (s1 <= 1 + 1e-12)).all()


# --------------------------------------------------------------------------------------
# comparison table and validation
# --------------------------------------------------------------------------------------


def test_method_comparison_table():
    rows = free_surface_method_comparison(n_side=16, repeats=1)
    cases = [r["case"].split()[0] for r in rows]
    assert cases == ["lattice", "disc", "jittered", "block", "hexagonal"]
    for r in rows:
        assert set(r) >= {"case", "n", "n_exact", "n_circle", "n_cheap", "circle_errors",
                          "cheap_errors", "agree", "circle_us", "cheap_us"}
        assert r["circle_us"] > 0 and r["cheap_us"] > 0
        assert r["cheap_errors"] == 0
    assert all(r["circle_errors"] == 0 for r in rows[:4])
    assert rows[4]["circle_errors"] == 2 * (16 // 2 - 1)


def test_bad_input():
    x, _ = _block(4)
    table = _table(x)
    with pytest.raises(ValueError, match="method"):
        detect_free_surface(x, table, 1.0, method="alpha_shape")
    with pytest.raises(ValueError, match="spacing"):
        detect_circle_coverage(x, table, 0.0)
    with pytest.raises(ValueError, match="radius_factor"):
        detect_circle_coverage(x, table, 1.0, radius_factor=-1)
    with pytest.raises(ValueError, match="n_test_points"):
        detect_circle_coverage(x, table, 1.0, n_test_points=2)
    with pytest.raises(ValueError, match="themselves"):
        detect_circle_coverage(x[:-1], table, 1.0)
    with pytest.raises(ValueError, match="themselves"):
        detect_neighbour_deficit(x, find_neighbors(x[:3], x, radius=2.2), 1.0)
    with pytest.raises(ValueError, match="NeighborTable"):
        detect_circle_coverage(x, (table.indptr, table.indices), 1.0)
    with pytest.raises(ValueError, match="NaN"):
        detect_neighbour_deficit(np.where(np.arange(16)[:, None] == 3, np.nan, x), table, 1.0)
    with pytest.raises(ValueError, match="n_reference"):
        detect_neighbour_deficit(x, table, 1.0, n_reference=0)
    with pytest.raises(ValueError, match="beta"):
        detect_neighbour_deficit(x, table, 1.0, beta=0)
    with pytest.raises(ValueError, match="asymmetry_threshold"):
        detect_neighbour_deficit(x, table, 1.0, asymmetry_threshold=1.5)


def test_empty_table_rows_and_self_pairs_only():
    x = np.array([[0.0, 0.0], [5.0, 0.0]])
    table = NeighborTable(np.array([0, 1, 2], dtype=np.int64), np.array([0, 1], dtype=np.int32), 2)
    for method in METHODS:
        assert detect_free_surface(x, table, 1.0, method=method).all()


# --------------------------------------------------------------------------------------
# the normal-cone scan (Marrone et al. 2010's confirmation step)
# --------------------------------------------------------------------------------------


def test_cone_scan_keeps_the_top_row_and_covers_the_interior():
    from mlsgalerkin.fluid.free_surface import open_along_normal
    x, _ = _block(8)
    table = _table(x, radius=2.6)
    up = np.tile([0.0, 1.0], (x.shape[0], 1))
    is_open = open_along_normal(x, table, np.arange(x.shape[0]), up)
    top = np.isclose(x[:, 1], x[:, 1].max())
    assert np.array_equal(is_open, top)
    # pointing sideways, only the column on that side is open
    right = np.tile([1.0, 0.0], (x.shape[0], 1))
    assert np.array_equal(open_along_normal(x, table, np.arange(x.shape[0]), right), np.isclose(x[:, 0], x[:, 0].max()))


def test_cone_scan_covers_a_sparse_patch_inside_a_disordered_block():
    # an interior particle next to a removed neighbour has a deficient neighbourhood but
    # particles in every direction: whatever its normal, the cone is covered
    from mlsgalerkin.fluid.free_surface import open_along_normal
    x, _ = _block(9)
    centre = np.argmin(np.linalg.norm(x - x.mean(0), axis=1))
    hole = np.argmin(np.linalg.norm(x - (x[centre] + [1.0, 0.0]), axis=1))
    x = np.delete(x, hole, axis=0)
    centre -= int(hole < centre)
    table = _table(x, radius=2.6)
    angles = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    assert not open_along_normal(x, table, np.full(16, centre), normals).any()


@pytest.mark.parametrize("seed", [0, 1])
def test_cone_scan_numba_matches_reference(seed):
    from mlsgalerkin.fluid.free_surface import open_along_normal, open_along_normal_reference
    rng = np.random.default_rng(seed)
    x, _ = _block(10)
    x += rng.uniform(-0.3, 0.3, x.shape)
    period = np.array([10.0, 0.0])
    x[:, 0] = np.mod(x[:, 0], 10.0)        # ten columns, seamless across x = 0
    table = find_neighbors(x, x, radius=2.6, period=period)
    cand = rng.permutation(x.shape[0])
    # normals roughly away from the nearer of the top and bottom rows: those rows are open
    n = np.sign(x[cand, 1:2] - 4.5) * [0.0, 1.0] + 0.3 * rng.normal(size=(cand.size, 2))
    n /= np.linalg.norm(n, axis=1)[:, None]
    for angle in (np.pi / 4, np.pi / 3):
        a = open_along_normal(x, table, cand, n, angle, period)
        b = open_along_normal_reference(x, table, cand, n, angle, period)
        assert np.array_equal(a, b) and 5 < a.sum() < 40


def test_cone_scan_refuses_a_bad_angle():
    from mlsgalerkin.fluid.free_surface import open_along_normal
    x, _ = _block(3)
    with pytest.raises(ValueError, match="half_angle"):
        open_along_normal(x, _table(x), [0], [[0.0, 1.0]], half_angle=2.0)
