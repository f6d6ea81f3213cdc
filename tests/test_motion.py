"""Prescribed rigid motion (translation and rotation about a point) and walls that move with it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.fluid import (
    FluidBody,
    Gravity,
    MonaghanViscosity,
    Phase,
    TaitPressure,
    WallBody,
    Walls,
    lattice,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.motion import Oscillation, PrescribedMotion
from mlsgalerkin.scene import Scene, SceneError
from mlsgalerkin.simulation import Simulation


def swinging(amplitude: float, omega: float, centre=(0.1, -0.2), drift=(0.03, -0.01)) -> PrescribedMotion:
    """θ = A sin ωt about ``centre`` while the centre drifts as ``d = drift · t²``."""
    dr = np.asarray(drift)
    return PrescribedMotion(
        displacement=lambda t: dr * t * t, velocity=lambda t: 2 * dr * t, acceleration=lambda t: 2 * dr,
        angle=lambda t: amplitude * math.sin(omega * t),
        angular_velocity=lambda t: amplitude * omega * math.cos(omega * t),
        angular_acceleration=lambda t: -amplitude * omega**2 * math.sin(omega * t),
        centre=centre,
    )


def _central(f, t, eps=1e-6):
    return (f(t + eps) - f(t - eps)) / (2 * eps)


@settings(max_examples=25, deadline=None)
@given(amplitude=st.floats(0.0, 1.2), omega=st.floats(0.5, 8.0), t=st.floats(0.0, 2.0),
       cx=st.floats(-1, 1), cy=st.floats(-1, 1))
def test_rotation_kinematics_are_the_derivatives_of_the_positions(amplitude, omega, t, cx, cy):
    m = swinging(amplitude, omega, centre=(cx, cy))
    x0 = np.array([[0.3, 0.1], [-0.2, 0.4], [cx, cy]])
    v = m.velocities(x0, t)
    a = m.accelerations(x0, t)
    np.testing.assert_allclose(v, _central(lambda s: m.positions(x0, s), t), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(a, _central(lambda s: m.velocities(x0, s), t), rtol=1e-6, atol=1e-6)
    # rigid: distances are kept, the normals turn and stay unit vectors
    x = m.positions(x0, t)
    assert np.linalg.norm(x[0] - x[1]) == pytest.approx(np.linalg.norm(x0[0] - x0[1]), rel=1e-12)
    n = m.rotate(np.array([[1.0, 0.0], [0.0, 1.0]]), t)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)
    assert m.check(2) == []


def test_oscillation_ramp_starts_at_rest_and_check_catches_wrong_derivatives():
    piston = Oscillation(stroke=0.1, period=2.0, direction=(2.0, 0.0), ramp=1.0)
    x0 = np.zeros((1, 2))
    for t in (0.0, 0.3, 0.99, 1.01, 1.7):
        np.testing.assert_allclose(piston.velocities(x0, t), _central(lambda s: piston.positions(x0, s), t), atol=1e-7)
        np.testing.assert_allclose(piston.accelerations(x0, t), _central(lambda s: piston.velocities(x0, s), t), atol=1e-6)
    assert np.all(piston.velocities(x0, 0.0) == 0) and np.all(piston.accelerations(x0, 0.0) == 0)
    assert piston.positions(x0, 1.5)[0, 0] == pytest.approx(0.05 * math.sin(math.pi * 1.5))  # unit direction
    wrong = PrescribedMotion(lambda t: np.array([t, 0.0]), lambda t: np.array([2.0, 0.0]), lambda t: np.zeros(2))
    assert any("velocity" in p and "finite difference" in p for p in wrong.check(2))
    assert "rotation is 2D only" in swinging(0.1, 1.0).check(3)[0]
    with pytest.raises(ValueError, match="period must be positive"):
        Oscillation(stroke=0.1, period=0.0)
    with pytest.raises(ValueError, match="together"):
        PrescribedMotion(displacement=lambda t: np.zeros(2))
    with pytest.raises(ValueError, match="centre"):
        PrescribedMotion(angle=lambda t: 0.0, angular_velocity=lambda t: 0.0, angular_acceleration=lambda t: 0.0)


def _flap_scene(motion, t_end=0.02):
    dx = 0.01
    water = FluidBody.block("water", (0.0, 0.0), (0.2, 0.1), dx, [Phase("water", 1000.0)])
    floor = WallBody("floor", lattice((-0.05, -0.03), (0.25, 0.0), dx), dx,
                     normals=np.tile([0.0, 1.0], (30 * 3, 1)))
    flap_x = lattice((-0.03, 0.0), (0.0, 0.15), dx)
    flap = WallBody("flap", flap_x, dx, normals=np.tile([1.0, 0.0], (len(flap_x), 1)), motion=motion)
    return Scene([water, floor, flap], [FluidScheme([TaitPressure(15.0), Gravity((0.0, -9.81)), Walls("free_slip"),
                                        MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=t_end), flap_x


def test_a_rotating_wall_moves_its_particles_velocities_accelerations_and_normals():
    motion = swinging(0.05, 20.0, centre=(0.0, 0.0), drift=(0.0, 0.0))
    scene, flap_x = _flap_scene(motion)
    sim = Simulation(scene)
    res = sim.run(progress=False)
    s = res.state.fluid
    rows = s.bodies["flap"]
    w = slice(rows.start - s.n_fluid, rows.stop - s.n_fluid)
    t = s.t
    np.testing.assert_allclose(s.x[rows], motion.positions(flap_x, t), rtol=0, atol=1e-15)
    np.testing.assert_allclose(s.wall_velocity[w], motion.velocities(flap_x, t), atol=1e-15)
    np.testing.assert_allclose(s.wall_acceleration[w], motion.accelerations(flap_x, t), atol=1e-12)
    np.testing.assert_allclose(s.wall_normals[w], motion.rotate(np.tile([1.0, 0.0], (len(flap_x), 1)), t))
    assert np.abs(s.wall_acceleration[w]).max() > 1.0  # θ'' = A ω² sin ωt: a real acceleration
    # the fixed floor stayed where it was, with no acceleration
    f = s.bodies["floor"]
    assert np.all(s.wall_acceleration[f.start - s.n_fluid:f.stop - s.n_fluid] == 0)
    assert "flap" in res.summary["fluid"]["moving_walls"][0]


def test_moving_walls_restart_bit_for_bit(tmp_path):
    motion = Oscillation(stroke=0.01, period=0.05, ramp=0.01)
    straight = Simulation(_flap_scene(motion, t_end=0.03)[0]).run(progress=False)
    Simulation(_flap_scene(motion, t_end=0.03)[0]).run(out=tmp_path, progress=False, max_steps=40)
    resumed = Simulation(_flap_scene(motion, t_end=0.03)[0]).run(out=tmp_path, progress=False, restart="latest")
    a, b = straight.state.fluid, resumed.state.fluid
    assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v) and np.array_equal(a.p, b.p)


def test_a_bad_motion_is_reported_with_the_scene():
    wrong = PrescribedMotion(lambda t: np.array([t * t, 0.0]), lambda t: np.array([t, 0.0]), lambda t: np.array([1.0, 0.0]))
    scene, _ = _flap_scene(wrong)
    with pytest.raises(SceneError, match="wall body 'flap'.*velocity at t"):
        Simulation(scene)
    with pytest.raises(ValueError, match="either a surface velocity"):
        WallBody("w", np.zeros((1, 2)), 0.01, velocity=np.array([1.0, 0.0]), motion=Oscillation(0.1, 1.0))
