"""Pressure sensors (:mod:`mlsgalerkin.fluid.sensors`) and the analysis of the dam break with
wall impact (:mod:`mlsgalerkin.problems.dam_break_impact`): a wall sensor reads the
hydrostatic pressure, a dry sensor reads zero, and the peak and ringing measures find what a
synthetic signal holds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mlsgalerkin.problems import dam_break_impact as impact

from mlsgalerkin.fluid import (
    FluidBody,
    Gravity,
    MonaghanViscosity,
    Phase,
    TaitEOS,
    TaitPressure,
    Walls,
    wall_box,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.fluid.sensors import pressure_at, sensor_points
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation

G = 9.81


def settled_tank(depth=0.3, width=0.3, dx=0.015, t_end=0.3):
    c0 = 10.0 * math.sqrt(2.0 * G * depth)
    eos = TaitEOS(1000.0, c0)
    water = FluidBody.block("water", (0.0, 0.0), (width, depth), dx, [Phase("water", 1000.0)])
    water.density[:] = eos.density(1000.0 * G * (depth - water.positions[:, 1]))
    walls = wall_box((0.0, 0.0), (width, 2 * depth), dx, layers=3)
    scene = Scene([water, walls], [FluidScheme([TaitPressure(c0), Gravity(), Walls("free_slip"), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=t_end, name="tank")
    return Simulation(scene).run(out=None, progress=False).state.fluid


def test_wall_sensors_read_the_hydrostatic_pressure_and_dry_ones_zero():
    s = settled_tank()
    heights = np.array([0.02, 0.08, 0.15, 0.22])
    pts = np.column_stack([np.full(heights.size, 0.3), heights])          # the right wall's face
    p = pressure_at(s, pts)
    exact = 1000.0 * G * (0.3 - heights)
    # the Shepard average over a support of about 2.6 dx: within 3 % of ρ g H everywhere
    assert np.abs(p - exact).max() < 0.03 * 1000.0 * G * 0.3
    assert pressure_at(s, [[0.3, 0.5]])[0] == 0.0                         # above the water: dry
    face = sensor_points((0.3, 0.0), 0.1, 0.11, axis=1, count=5)
    np.testing.assert_allclose(face[:, 1], 0.1 + 0.002 * (np.arange(5) + 0.5))
    assert np.all(face[:, 0] == 0.3)


def test_ringing_period_and_running_mean_on_a_synthetic_impact():
    T = np.linspace(2.0, 4.0, 4001)
    ringing = 0.034
    smooth = np.where(T > 2.4, 2.6 * np.exp(-(T - 2.4) / 0.5), 0.0)
    y = smooth + np.where(T > 2.4, 1.5 * np.sin(2 * math.pi * (T - 2.4) / ringing), 0.0)
    period = impact.ringing_period(T, y, 2.5, 3.5)
    assert period == pytest.approx(ringing, rel=0.03)
    mean = impact.running_mean(T, y, period)
    late = (T > 2.6) & (T < 3.8)
    assert np.abs(mean - smooth)[late].max() < 0.05 * 2.6                # one period's mean removes it
    assert impact.ringing_period(T[:10], y[:10], 2.0, 2.01) != impact.ringing_period(T[:10], y[:10], 2.0, 2.01)


def test_reference_and_sensor_heights():
    ref = impact.load_reference()
    assert sorted(ref) == ["P1", "P2", "P3", "P4"]
    assert all(np.all(np.diff(v[:, 0]) >= 0) for v in ref.values())
    assert ref["P1"][:, 1].max() == pytest.approx(2.59, abs=0.01)
    lo, hi = impact.sensor_heights(impact.Parameters(height=0.3))[0]
    assert (lo + hi) / 2 == pytest.approx(0.003) and hi - lo == pytest.approx(0.0042)
