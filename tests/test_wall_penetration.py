"""Wall penetration: the surface offsets of wall layers, the depth of fluid particles behind a wall
surface (numba against numpy), and its report in the time series, the summary and a warning."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mlsgalerkin.fluid import FluidBody, Gravity, Phase, TaitPressure, Walls, lattice, wall_box
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
    d = penetration_depths(nb.indptr, nb.indices, x, len(fluid), box.normals, off)
    np.testing.assert_allclose(d, penetration_depths_reference(nb.indptr, nb.indices, x, len(fluid), box.normals, off),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(d[:5], [0.0, 0.2 * DX, 0.5 * DX, 0.9 * DX, 1.7 * DX], atol=1e-12)
    assert np.all(d[5:][fluid[5:, 1] > 0] == 0)  # above the floor: no penetration


def test_penetration_is_reported_in_time_series_summary_and_warned():
    water = FluidBody.block("water", (0.0, 0.0), (0.1, 0.05), DX, [Phase("water", 1000.0)])
    # one particle already 0.7 spacings inside the floor, midway between two columns of wall
    # particles: more than half a spacing from each, so the geometry check lets it through
    water.positions[3] = (0.03, -0.7 * DX)
    scene = Scene([water, wall_box((0.0, 0.0), (0.1, 0.1), DX)], [FluidScheme([TaitPressure(10.0), Gravity(), Walls()])], t_end=0.002)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = Simulation(scene).run(progress=False)
    ts = res.timeseries
    assert ts["wall_penetrations"][0] >= 1 and ts["max_wall_penetration_dx"][0] == pytest.approx(0.7, abs=0.05)
    report = res.summary["fluid"]["wall_penetration"]
    assert report["max_depth_dx"] >= 0.65 and report["warned"] and report["threshold_dx"] == 0.5
    assert any(issubclass(w.category, WallPenetrationWarning) and "walls are leaking" in str(w.message)
               for w in caught)
