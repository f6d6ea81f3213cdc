"""The geometric volume of the fluid (union of the particles' cells, gaps closed) on known cases,
and the pair-distance statistics (numba against numpy, and on known cases)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mlsgalerkin.fluid import lattice, wall_box
from mlsgalerkin.fluid.distribution import (
    AT_FLOOR,
    CLOSED_GAP,
    CLUMP_DISTANCE,
    NEIGHBOUR_CLASSES,
    PIXELS_PER_SPACING,
    cell_volumes,
    geometric_volume,
    occupancy,
    pair_statistics,
    pair_statistics_reference,
    volume_error,
    volume_error_by_class,
)
from mlsgalerkin.neighbors import find_neighbors

DX = 0.01


@pytest.mark.parametrize("dim, upper", [(1, (0.37,)), (2, (0.4, 0.2)), (3, (0.12, 0.1, 0.08))])
def test_a_lattice_block_is_n_cells(dim, upper):
    x = lattice((0.0,) * dim, upper, DX) + 0.00037  # any offset against the grid
    v = geometric_volume(x, DX)
    assert v == pytest.approx(len(x) * DX**dim, rel=5e-3)
    assert v == pytest.approx(len(x) * DX**dim, rel=1e-12)  # measured: exact (whole pixels per side)


@pytest.mark.parametrize("wobble", [1e-12, -1e-12])
def test_a_stray_particle_does_not_set_the_grid_of_a_flat_boundary(wobble):
    """A block 84 cells long resting on a wall, with one particle an eighth of a spacing below the
    rest: the grid follows the lattice's faces, not the stray particle, so a 10⁻¹² m wobble of the
    others cannot flip a whole row of pixels centred on their faces in or out (the grid taken from
    the lowest particle read 1.1 % less for one sample of a gravity current 84 cells long)."""
    x = lattice((0.0, 0.0), (0.84, 0.1), DX)
    x[1:, 1] += wobble
    x[0] -= 0.125 * DX
    assert geometric_volume(x, DX) == pytest.approx(len(x) * DX**2, rel=2e-3)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**31 - 1), dim=st.sampled_from([2, 3]))
def test_a_jittered_lattice_is_n_cells_within_one_percent(seed, dim):
    rng = np.random.default_rng(seed)
    # measured over 60 seeds: mean error -0.02 % (2D, 800 particles) and -0.01 % (3D, 1800), spread
    # (standard deviation) 0.18 % and 0.20 %, the largest 0.38 % and 0.52 % (with the grid on the
    # lowest faces' mean phase; 0.19 % and 0.25 %, 0.55 % and 0.63 % with the grid on the lowest
    # particle)
    upper = (0.4, 0.2) if dim == 2 else (0.15, 0.12, 0.1)
    x = lattice((0.0,) * dim, upper, DX)
    x = x + rng.uniform(-0.2, 0.2, x.shape) * DX
    assert geometric_volume(x, DX) == pytest.approx(len(x) * DX**dim, rel=1e-2)


@pytest.mark.parametrize("dim, axis", [(2, 0), (2, 1), (3, 2)])
def test_a_block_compressed_by_ten_percent_reads_ten_percent_less(dim, axis):
    upper = [0.1] * dim
    upper[axis] = 0.6
    x = lattice((0.0,) * dim, tuple(upper), DX)
    x[:, axis] *= 0.9
    n = 60  # particles along the compressed axis: their span shrinks by 10 %, the outer half cells keep theirs
    exact = (0.9 * (n - 1) + 1.0) / n
    ratio = geometric_volume(x, DX) / (len(x) * DX**dim)
    assert ratio == pytest.approx(0.9, abs=5e-3)
    assert abs(ratio - exact) <= 1.0 / (PIXELS_PER_SPACING * n) + 1e-12   # the rounding: at most one pixel per side


def test_a_block_stretched_apart_is_not_closed_beyond_the_gap():
    x = lattice((0.0, 0.0), (0.2, 0.1), DX)
    filled = geometric_volume(1.4 * x, DX)  # gaps of 0.4 spacings between the cells: the closing fills them
    # gaps of 0.8 spacings: left open, the union is the cells alone
    assert geometric_volume(1.8 * x, DX) == pytest.approx(len(x) * DX**2, rel=1e-12)
    assert filled > 1.8 * len(x) * DX**2


@pytest.mark.parametrize("gap, closed_share", [(0.45, 1.0), (0.55, 0.8), (0.625, 0.5), (0.7, 0.2), (0.8, 0.0)])
def test_a_gap_is_closed_below_its_threshold_on_average_over_the_phase(gap, closed_share):
    """Two particles ``(1 + w) Δx`` apart along x, far above a lattice block that sets the pixel
    grid, at 100 phases against the pixels: the gap between their cells (``⌊4w⌋`` or ``⌈4w⌉``
    pixels) is closed always below 0.5 spacings, never from 0.75, and in a share ``3 − 4w`` of the
    phases between (:func:`closing_radius`): on average below ``CLOSED_GAP`` = 0.625 spacings."""
    block = lattice((0.0, 0.0), (0.1, 0.08), DX)
    pixel = DX / PIXELS_PER_SPACING
    shares = []
    for phase in (np.arange(100) + 0.5) / 100:
        x0 = 0.5 * DX + 3 * DX + phase * pixel            # the pair's left cell face at this phase of the grid
        pair = np.array([[x0, 0.5003], [x0 + (1.0 + gap) * DX, 0.5003]])   # y off the pixel centres
        v = geometric_volume(np.vstack([block, pair]), DX) / DX**2 - len(block) - 2
        assert v == pytest.approx(0.0, abs=1e-9) or v == pytest.approx(gap, abs=1.01 / PIXELS_PER_SPACING)
        shares.append(v > 1e-9)
    assert np.mean(shares) == pytest.approx(closed_share, abs=0.03)
    assert CLOSED_GAP == 0.625


def test_splashes_count_their_own_cell():
    block = lattice((0.0, 0.0), (0.1, 0.05), DX)
    splashes = np.array([[0.5, 0.5], [0.8, 0.123], [-0.3, 0.77]])
    x = np.vstack([block, splashes])
    assert geometric_volume(x, DX) == pytest.approx((len(block) + 3) * DX**2, rel=1e-12)
    assert geometric_volume(splashes[:1], DX) == pytest.approx(DX**2, rel=1e-12)
    assert geometric_volume(np.zeros((0, 2)), DX) == 0.0


def test_a_disc_is_its_area():
    x = lattice((-0.2, -0.2), (0.2, 0.2), DX)
    x = x[np.einsum("ij,ij->i", x, x) < 0.15**2]
    # the union of the cells is the staircase disc of len(x) cells exactly
    # (concave steps of the staircase are one spacing wide: the closing leaves them open)
    assert geometric_volume(x, DX) == pytest.approx(len(x) * DX**2, rel=1e-12)


def test_far_splashes_count_their_own_cells_and_leave_the_bulk_alone(rng):
    """A ragged fluid (a jittered lattice) plus splashes flown far above, beside and below it:
    the volume is the fluid's alone plus one cell per splash, at the full resolution. (One grid
    over the bounding box had to be coarsened to two pixels per spacing, whose closing fills gaps
    a whole spacing wide: a dam break on a beam with four particles fallen 22 m read +17 %, and
    the lowest splash, not the floor, set the pixel phase.)"""
    bulk = lattice((0.0, 0.0), (0.3, 0.15), DX)
    bulk = bulk + rng.uniform(-0.2, 0.2, bulk.shape) * DX
    splashes = np.array([[50.0, 30.0], [-3.0, 0.07], [0.11, -22.0], [0.4, -22.0]])
    alone = geometric_volume(bulk, DX)
    assert geometric_volume(np.vstack([bulk, splashes]), DX) == pytest.approx(alone + 4 * DX**2, rel=1e-12)


@pytest.mark.parametrize("dim, tile", [(1, 40), (2, 24), (3, 16)])
def test_tiles_count_what_one_grid_counts(dim, tile, rng):
    """The tiled count equals the count of one grid over the bounding box (:func:`occupancy`),
    for tiles far smaller than the fluid (each particle's cell and closing reach cut by tile
    edges in every direction)."""
    from mlsgalerkin.fluid.distribution import PIXELS_PER_SPACING, occupancy

    upper = {1: (0.3,), 2: (0.12, 0.09), 3: (0.05, 0.04, 0.04)}[dim]
    x = lattice((0.0,) * dim, upper, DX)
    x = x * 1.15 + rng.uniform(-0.3, 0.3, x.shape) * DX   # gaps of all widths, some closed, some open
    grid, pixel = occupancy(x, DX)
    assert pixel == DX / PIXELS_PER_SPACING                 # not coarsened
    assert geometric_volume(x, DX, tile=tile) == np.count_nonzero(grid) * pixel**dim
    assert geometric_volume(x, DX) == np.count_nonzero(grid) * pixel**dim


def test_a_tile_narrower_than_a_cell_is_refused():
    with pytest.raises(ValueError, match="larger tile"):
        geometric_volume(lattice((0.0, 0.0), (0.05, 0.05), DX), DX, tile=4)


# ------------------------------------------------------------------ pair statistics
def _scene(rng, jitter=0.3):
    box = wall_box((0.0, 0.0), (0.2, 0.1), DX, layers=2)
    fluid = lattice((0.0, 0.0), (0.2, 0.06), DX)
    fluid = fluid + rng.uniform(-jitter, jitter, fluid.shape) * DX
    return fluid, box


def test_pair_statistics_numba_matches_numpy(rng):
    fluid, box = _scene(rng)
    fluid[10] = fluid[11] + (0.1 * DX, 0.05 * DX)   # one clumped pair
    x = np.ascontiguousarray(np.vstack([fluid, box.positions]))
    nb = find_neighbors(x, x, radius=2.6 * DX)
    got = pair_statistics(nb.indptr, nb.indices, x, len(fluid), DX)
    ref = pair_statistics_reference(nb.indptr, nb.indices, x, len(fluid), DX)
    assert got == ref
    assert got.min_pair_distance_dx == pytest.approx(np.hypot(0.1, 0.05), rel=1e-9)
    assert got.clumped_pairs >= 1


def test_pair_statistics_of_a_lattice_and_known_pairs():
    fluid = lattice((0.0, 0.0), (0.2, 0.06), DX)
    box = wall_box((0.0, 0.0), (0.2, 0.1), DX, layers=2)
    x = np.ascontiguousarray(np.vstack([fluid, box.positions]))
    nb = find_neighbors(x, x, radius=2.6 * DX)
    s = pair_statistics(nb.indptr, nb.indices, x, len(fluid), DX)
    assert s.min_pair_distance_dx == pytest.approx(1.0) and s.clumped_pairs == 0
    assert s.min_wall_distance_dx == pytest.approx(1.0)   # first layer half a spacing behind the surface
    # three particles within 0.3 spacings of each other: three clumped pairs, each counted once
    fluid[50] = fluid[51] + (0.2 * DX, 0.0)
    fluid[52] = fluid[51] + (0.0, 0.25 * DX)
    x = np.ascontiguousarray(np.vstack([fluid, box.positions]))
    nb = find_neighbors(x, x, radius=2.6 * DX)
    s = pair_statistics(nb.indptr, nb.indices, x, len(fluid), DX)
    assert s.clumped_pairs == 3 and s.min_pair_distance_dx == pytest.approx(0.2)
    assert CLUMP_DISTANCE == 0.5


def test_pair_statistics_without_walls_or_pairs():
    x = np.array([[0.0, 0.0], [1.0, 0.0]])
    nb = find_neighbors(x, x, radius=0.1)
    s = pair_statistics(nb.indptr, nb.indices, x, 2, DX)
    assert s.min_pair_distance_dx == np.inf and s.min_wall_distance_dx == np.inf and s.clumped_pairs == 0


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_occupancy_numba_matches_scipy(dim, rng):
    from mlsgalerkin.fluid.distribution import occupancy, occupancy_reference

    upper = {1: (0.2,), 2: (0.1, 0.06), 3: (0.05, 0.04, 0.03)}[dim]
    x = lattice((0.0,) * dim, upper, DX)
    x = x * 1.2 + rng.uniform(-0.3, 0.3, x.shape) * DX   # gaps of all widths, some closed, some open
    x = np.vstack([x, x[:1] + 0.3])                       # and a splash
    grid, _ = occupancy(x, DX)
    ref = occupancy_reference(x, DX)
    assert grid.shape == ref.shape and np.array_equal(grid, ref)


def test_the_volume_error_compares_the_cells_with_the_masses_over_the_densities():
    x = lattice((0.0, 0.0), (0.4, 0.2), DX)
    M = np.full(x.shape[0], 1000.0 * DX**2)
    vgeo, err = volume_error(x, M, np.full(x.shape[0], 1000.0), DX)
    assert vgeo == pytest.approx(0.08, rel=1e-12) and abs(err) < 1e-12
    assert volume_error(x, M, np.full(x.shape[0], 1100.0), DX)[1] == pytest.approx(0.1, rel=1e-12)  # too dense: voids
    assert volume_error(x[:0], M[:0], M[:0], DX) == (0.0, 0.0)


@pytest.mark.parametrize("dim, upper", [(1, (0.37,)), (2, (0.4, 0.2)), (3, (0.12, 0.1, 0.08))])
def test_each_particle_of_a_lattice_gets_its_own_cell(dim, upper):
    x = lattice((0.0,) * dim, upper, DX) + 0.00037
    shares = cell_volumes(x, DX)
    assert shares.shape == (len(x),)
    np.testing.assert_allclose(shares, DX**dim, rtol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_shares_add_up_to_the_geometric_volume(dim):
    """On a jittered block the shares differ from particle to particle, and add up to the closed
    union that :func:`geometric_volume` measures (its tiles count the same pixels)."""
    rng = np.random.default_rng(5)
    x = lattice((0.0,) * dim, (0.3, 0.2, 0.1)[:dim], DX)
    x = x + rng.uniform(-0.3, 0.3, x.shape) * DX
    shares = cell_volumes(x, DX)
    grid, pixel = occupancy(x, DX)
    assert shares.sum() == pytest.approx(float(grid.sum()) * pixel**dim, rel=1e-12)
    assert shares.sum() == pytest.approx(geometric_volume(x, DX), rel=1e-12)
    assert shares.std() > 0.05 * DX**dim


@pytest.mark.parametrize("dim, tile", [(1, 40), (2, 24), (3, 16)])
def test_tiled_shares_are_the_shares_of_one_grid(dim, tile, rng):
    """Tiles far smaller than the fluid split the union exactly as one grid over the bounding
    box does: every share the same to the last bit, and their sum the tiled geometric volume."""
    upper = {1: (0.3,), 2: (0.12, 0.09), 3: (0.05, 0.04, 0.04)}[dim]
    x = lattice((0.0,) * dim, upper, DX)
    x = x * 1.15 + rng.uniform(-0.3, 0.3, x.shape) * DX
    one_grid = cell_volumes(x, DX, tile=10**6)
    tiled = cell_volumes(x, DX, tile=tile)
    np.testing.assert_array_equal(tiled, one_grid)
    assert tiled.sum() == pytest.approx(geometric_volume(x, DX, tile=tile), rel=1e-12)


def test_a_splash_far_from_the_bulk_gets_its_own_cell_in_3d(rng):
    """A 3D block with drops flown metres away: each drop gets its own cell, the block's shares
    are those without the drops, at full resolution (one grid over that bounding box would hold
    10^12 voxels)."""
    block = lattice((0.0, 0.0, 0.0), (0.1, 0.08, 0.06), DX) + rng.uniform(-0.2, 0.2, (1, 3)) * DX
    block = block + rng.uniform(-0.25, 0.25, block.shape) * DX
    drops = np.array([[3.0, 0.2, 0.1], [-2.5, 4.0, 1.0], [0.05, 0.04, -6.0]])
    shares = cell_volumes(np.vstack([block, drops]), DX)
    np.testing.assert_allclose(shares[-3:], DX**3, rtol=1e-12)
    np.testing.assert_array_equal(shares[:-3], cell_volumes(block, DX))
    assert shares.sum() == pytest.approx(geometric_volume(np.vstack([block, drops]), DX), rel=1e-12)


def test_a_stretched_sheet_reads_its_closed_gaps():
    """A row of particles 1.3 spacings apart: the closing fills the 0.3-spacing gaps between their
    cells, and each inner particle gets its cell and half of each gap beside it, 1.3 Δx² on average; 1.8
    spacings apart, the gaps stay open and each particle gets its own cell."""
    for stretch, share in ((1.3, 1.3), (1.8, 1.0)):
        x = np.c_[np.arange(20) * stretch * DX, np.zeros(20)] + 0.00037
        inner = cell_volumes(x, DX)[2:-2] / DX**2
        assert inner.mean() == pytest.approx(share, abs=0.02)
        # a gap of 1.2 pixels holds one or two pixel columns, each a quarter of a cell
        np.testing.assert_allclose(inner, share, atol=1.0 / PIXELS_PER_SPACING + 1e-9)


def test_no_particles_no_shares():
    assert cell_volumes(np.zeros((0, 2)), DX).shape == (0,)


def test_volume_error_by_class_puts_a_stretched_chain_at_the_floor():
    """A lattice block with a chain of particles 1.4 spacings apart above it (a jet stretched at
    ``ρ0``): the closing counts the chain's 0.4-spacing gaps, so the error is positive; the chain
    (two neighbours each) carries it in the sheets' class, and flagged as at the floor, there too.
    The block alone has no error in any class; no particles is refused."""
    dx = 0.01
    block = lattice((0.0, 0.0), (0.3, 0.1), dx) + 0.00037
    lone = volume_error_by_class(block, np.full(len(block), dx**2), dx)
    assert lone["volume_error"] == pytest.approx(0.0, abs=1e-12)
    assert all(lone[name]["contribution"] == pytest.approx(0.0, abs=1e-12) for name, _, _ in NEIGHBOUR_CLASSES)
    chain = np.c_[0.05 + 1.4 * dx * np.arange(12), np.full(12, 0.2)] + 0.00037
    x = np.vstack([block, chain])
    floor = np.arange(len(x)) >= len(block)
    split = volume_error_by_class(x, np.full(len(x), dx**2), dx, at_floor=floor)
    expected = 11 * 0.4 * dx**2 / (len(x) * dx**2)          # eleven gaps of 0.4 of a cell, closed
    assert split["volume_error"] == pytest.approx(expected, rel=0.05)
    assert sum(split[name]["contribution"] for name, _, _ in NEIGHBOUR_CLASSES) == pytest.approx(
        split["volume_error"], abs=1e-12)
    assert split["sheets and ragged surface"]["contribution"] == pytest.approx(split["volume_error"], rel=1e-9)
    assert split[AT_FLOOR]["contribution"] == pytest.approx(split["volume_error"], rel=1e-9)
    assert split[AT_FLOOR]["particles"] == pytest.approx(12 / len(x))
    assert split["drops"]["particles"] == 0.0 and np.isnan(split["drops"]["excess_per_particle"])
    with pytest.raises(ValueError, match="positive total volume"):
        volume_error_by_class(np.zeros((0, 2)), np.zeros(0), dx)

