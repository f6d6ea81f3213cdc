"""Wall penetration: the surface offsets of wall layers, the depth of fluid particles behind a wall
surface (numba against numpy), and its report in the time series, the summary and a warning."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mlsgalerkin.fluid import FluidBody, Gravity, MonaghanViscosity, Phase, TaitPressure, Walls, lattice, wall_box
from mlsgalerkin.fluid.penetration import (
    penetration_depths,
    penetration_depths_reference,
    surface_offsets,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.fluid.solver import WallPenetrationWarning
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation

DX = 0.01


def test_surface_offsets_count_the_layers_in_front():
    box = wall_box((0.0, 0.0), (0.2, 0.1), DX, layers=3)
    off = surface_offsets(box.positions, box.normals, DX)
    # on the floor, below the middle: layers at y = -0.005, -0.015, -0.025 are 0.5, 1.5, 2.5 dx behind
    floor = (np.abs(box.positions[:, 0] - 0.105) < 1e-9) & (box.positions[:, 1] < 0)
    np.testing.assert_allclose(np.sort(off[floor]), [0.5 * DX, 1.5 * DX, 2.5 * DX])
    side = (np.abs(box.positions[:, 1] - 0.055) < 1e-9) & (box.positions[:, 0] > 0.2)
    np.testing.assert_allclose(np.sort(off[side]), [0.5 * DX, 1.5 * DX, 2.5 * DX])


def test_depths_behind_a_floor_numba_matches_numpy(rng):
    box = wall_box((0.0, 0.0), (0.2, 0.1), DX, layers=3)
    fluid = lattice((0.0, 0.0), (0.2, 0.05), DX)
    fluid = fluid + rng.uniform(-0.45, 0.45, fluid.shape) * DX
    fluid[:5, 1] = -np.array([0.0, 0.2, 0.5, 0.9, 1.7]) * DX  # pushed into the floor
    fluid[:5, 0] = 0.05 + np.arange(5) * 0.02
    x = np.ascontiguousarray(np.vstack([fluid, box.positions]))
    nb = find_neighbors(x, x, radius=2.6 * DX)
    off = surface_offsets(box.positions, box.normals, DX)
    d = penetration_depths(nb.indptr, nb.indices, x, len(fluid), box.normals, off, DX)
    np.testing.assert_allclose(d, penetration_depths_reference(nb.indptr, nb.indices, x, len(fluid), box.normals, off,
                                                               DX), rtol=0, atol=1e-15)
    np.testing.assert_allclose(d[:5], [0.0, 0.2 * DX, 0.5 * DX, 0.9 * DX, 1.7 * DX], atol=1e-12)
    assert np.all(d[5:][fluid[5:, 1] > 0] == 0)  # above the floor: no penetration


def test_penetration_is_reported_in_time_series_summary_and_warned():
    water = FluidBody.block("water", (0.0, 0.0), (0.1, 0.05), DX, [Phase("water", 1000.0)])
    # one particle already 0.7 spacings inside the floor, midway between two columns of wall
    # particles: more than half a spacing from each, so the geometry check lets it through
    water.positions[3] = (0.03, -0.7 * DX)
    scene = Scene([water, wall_box((0.0, 0.0), (0.1, 0.1), DX)], [FluidScheme([TaitPressure(10.0), Gravity(), Walls()], stabilisation="as_listed")], t_end=0.002)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = Simulation(scene).run(progress=False)
    ts = res.timeseries
    assert ts["wall_penetrations"][0] >= 1 and ts["max_wall_penetration_dx"][0] == pytest.approx(0.7, abs=0.05)
    report = res.summary["fluid"]["wall_penetration"]
    assert report["max_depth_dx"] >= 0.65 and report["warned"] and report["threshold_dx"] == 0.5
    assert any(issubclass(w.category, WallPenetrationWarning) and "walls are leaking" in str(w.message)
               for w in caught)


def test_only_particles_inside_a_wall_count_not_those_over_its_top_or_outside_it():
    """An open tank's end wall, 4 spacings high and 3 layers thick (x from 0.2 to 0.23): a particle
    over its top or down its outer face is not inside it; one inside it reports its depth."""
    box = wall_box((0.0, 0.0), (0.2, 0.04), DX, layers=3)
    fluid = np.array([
        [0.215, 0.05],          # over the top of the end wall, inside its thickness (one spacing above the top row)
        [0.205, 0.047],         # just over the top row (0.035 + 0.6 dx + ...): beside the top cell
        [0.238, 0.01],          # down the outer face: beyond the back of the outer layer
        [0.26, -0.02],          # further outside, below the floor's level
        [0.2035, 0.02],         # inside the wall, 0.35 dx behind the surface
        [0.212, 0.025],         # inside the wall, 1.2 dx behind the surface (second layer)
        [0.1, 0.02],            # in the tank
    ])
    x = np.ascontiguousarray(np.vstack([fluid, box.positions]))
    nb = find_neighbors(x, x, radius=2.6 * DX)
    off = surface_offsets(box.positions, box.normals, DX)
    d = penetration_depths(nb.indptr, nb.indices, x, len(fluid), box.normals, off, DX)
    ref = penetration_depths_reference(nb.indptr, nb.indices, x, len(fluid), box.normals, off, DX)
    np.testing.assert_allclose(d, ref, rtol=0, atol=1e-15)
    np.testing.assert_allclose(d, [0.0, 0.0, 0.0, 0.0, 0.35 * DX, 1.2 * DX, 0.0], atol=1e-12)
    # the half-space test alone (no spacing) counted the particles over and outside the wall
    half_space = penetration_depths(nb.indptr, nb.indices, x, len(fluid), box.normals, off)
    np.testing.assert_allclose(half_space[:3], [1.5 * DX, 0.5 * DX, 3.8 * DX], atol=1e-12)


def test_water_overflowing_an_open_tank_is_not_a_leak():
    """Water twice as deep as the tank's walls are high spills over both end walls and falls down
    their outer faces: no penetration is reported and no leak is warned about, while the
    half-space test counts the water outside as several spacings behind the walls."""
    water = FluidBody.block("water", (0.0, 0.0), (0.2, 0.12), DX, [Phase("water", 1000.0)])
    box = wall_box((0.0, 0.0), (0.2, 0.04), DX)
    scene = Scene([water, box], [FluidScheme([TaitPressure(15.0, negative_pressure="cavitate"), Gravity(), Walls(),
                                              MonaghanViscosity(0.1)], stabilisation="as_listed",
                                             # kept, to fall below the floor along the walls' outer
                                             # faces (by default they are taken out past the domain)
                                             domain_exit=False)], t_end=0.2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = Simulation(scene).run(progress=False)
    x = res.state.systems["fluid"].x
    outside = (x[: water.n, 0] > 0.23) | (x[: water.n, 0] < -0.03)
    assert outside.sum() >= 20 and x[: water.n, 1][outside].min() < 0.0   # spilled and fell below the wall's top
    report = res.summary["fluid"]["wall_penetration"]
    assert report["max_depth_dx"] < 0.5 and not report["warned"]
    assert res.timeseries["max_wall_penetration_dx"].max() < 0.5
    assert not any(issubclass(w.category, WallPenetrationWarning) for w in caught)
    s = res.state.systems["fluid"]
    off = surface_offsets(box.positions, box.normals, DX)
    nb = find_neighbors(s.x, s.x, radius=2.6 * DX)
    half_space = penetration_depths(nb.indptr, nb.indices, s.x, s.n_fluid, s.wall_normals, off)
    assert half_space.max() > 2.0 * DX
