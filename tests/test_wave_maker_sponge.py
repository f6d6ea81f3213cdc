"""The wave maker's sponge: wired into the scene only when asked for, and the measurement
window it opens (the far wall's reflection no longer ends it)."""

import math

import numpy as np
from mlsgalerkin.problems import wave_maker as wm

from mlsgalerkin.fluid.sponge import SpongeZone


def _effects(p):
    scene = wm.make_scene(p)
    return [e for scheme in scene.schemes for e in scheme.effects]


def test_no_sponge_by_default_and_the_far_wall_reflection_ends_the_window():
    p = wm.Parameters(dx=0.02, tank_length=2.0, t_end=20.0)
    assert not any(isinstance(e, SpongeZone) for e in _effects(p))
    _, t_to = wm.measurement_window(p)
    cg = wm.group_velocity(p.period, p.depth, p.g)
    assert math.isclose(t_to, (2 * p.tank_length - p.probe_x) / cg - p.period)
    assert t_to < p.t_end


def test_a_sponge_lies_over_the_tanks_last_stretch_and_opens_the_window_to_the_end():
    p = wm.Parameters(dx=0.02, tank_length=2.0, t_end=20.0, sponge_length=0.8, sponge_rate=12.0)
    zones = [e for e in _effects(p) if isinstance(e, SpongeZone)]
    assert len(zones) == 1
    z = zones[0]
    assert math.isclose(z.start, 1.2) and math.isclose(z.length, 0.8) and z.axis == 0
    assert math.isclose(z.rate, 12.0 / p.period)
    assert wm.measurement_window(p)[1] == p.t_end


def test_harmonic_fit_recovers_a_two_harmonic_signal():
    t = np.linspace(3.0, 9.0, 601)
    omega = 2 * math.pi
    eta = 0.001 + 0.01 * np.cos(omega * t - 0.3) + 0.0008 * np.sin(2 * omega * t)
    coef, resid = wm.harmonic_fit(t, eta, omega)
    assert math.isclose(2 * math.hypot(coef[1], coef[2]), 0.02, rel_tol=1e-9)
    assert math.isclose(coef[0], 0.001, rel_tol=1e-9)
    assert np.abs(resid).max() < 1e-12
