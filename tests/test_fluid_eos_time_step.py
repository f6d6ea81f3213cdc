"""Tait equation of state (one implementation for the effect, the initial state and the energy)
and the explicit time-step limits."""

from __future__ import annotations

import numpy as np
import pytest

import math

from mlsgalerkin.fluid import (
    MachNumberWarning,
    TaitEOS,
    acoustic_limit,
    bulk_viscosity_limit,
    force_limit,
    hydrostatic_density,
    pair_viscosity_limit,
    tait_density,
    tait_pressure,
    tait_stored_energy,
    viscous_limit,
)


def test_tait_reference_state_inverse_and_sound_speed():
    eos = TaitEOS(rho0=1000.0, c0=20.0)
    assert eos.B == pytest.approx(1000.0 * 400.0 / 7.0)
    assert float(eos.pressure(1000.0)) == 0.0
    rho = np.linspace(980.0, 1030.0, 11)
    np.testing.assert_allclose(eos.density(eos.pressure(rho)), rho, rtol=1e-13)
    # c^2 = dp/drho, checked by central differences
    d = 1e-4
    dpdrho = (eos.pressure(rho + d) - eos.pressure(rho - d)) / (2 * d)
    np.testing.assert_allclose(eos.sound_speed(rho) ** 2, dpdrho, rtol=1e-7)
    assert float(eos.sound_speed(1000.0)) == pytest.approx(20.0)


def test_mach_number_rule_and_warning():
    eos = TaitEOS.from_max_velocity(1000.0, u_max=np.sqrt(2 * 9.81 * 0.6))
    assert eos.check_mach(np.sqrt(2 * 9.81 * 0.6)) == pytest.approx(0.1)
    with pytest.warns(MachNumberWarning, match="raise c0 to at least 20"):
        TaitEOS(1000.0, 10.0).check_mach(2.0)


@pytest.mark.parametrize("kwargs", [{"rho0": 0.0, "c0": 1.0}, {"rho0": 1.0, "c0": -1.0},
                                    {"rho0": 1.0, "c0": 1.0, "gamma": 0.5}])
def test_tait_rejects_bad_parameters(kwargs):
    with pytest.raises(ValueError, match="TaitEOS"):
        TaitEOS(**kwargs)


def test_density_below_cavitation_limit_raises():
    eos = TaitEOS(1000.0, 20.0)
    with pytest.raises(ValueError, match="cavitation"):
        eos.density(-2 * eos.B)


def test_hydrostatic_density_per_phase_and_stored_energy():
    rho0 = np.array([1000.0, 1500.0])
    depth = np.array([0.3, 0.3])
    rho = hydrostatic_density(rho0, depth, 9.81, 10.0)
    # p(rho) gives back the hydrostatic pressure of each phase
    np.testing.assert_allclose(tait_pressure(rho / rho0, rho0, 10.0), rho0 * 9.81 * depth, rtol=1e-12)
    np.testing.assert_allclose(tait_density(rho0 * 9.81 * depth, rho0, 10.0), rho, rtol=0, atol=0)
    # the stored energy is the work of compression: d e / d rho = p / rho^2 per unit mass
    r = np.linspace(0.97, 1.03, 7)
    M = np.ones_like(r)
    e = tait_stored_energy(M, r, 10.0)
    assert e[3] == 0.0 and np.all(e >= 0)
    d = 1e-6
    de = (tait_stored_energy(M, r + d, 10.0) - tait_stored_energy(M, r - d, 10.0)) / (2 * d)  # per unit ratio
    np.testing.assert_allclose(de, tait_pressure(r, 1.0, 10.0) / r**2, rtol=1e-6, atol=1e-9)
    with pytest.raises(ValueError, match="cavitation"):
        tait_density(-1e9, 1000.0, 10.0)


def test_time_step_limits():
    h = np.full(4, 0.01)
    v = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, -2.0], [0.0, 0.0]])
    assert acoustic_limit(h, np.full(4, 20.0), v) == pytest.approx(0.4 * 0.01 / 22.0)
    assert viscous_limit(h, np.full(4, 1e-6)) == pytest.approx(0.125 * 1e-4 / 1e-6)
    assert viscous_limit(h, np.zeros(4)) == np.inf
    assert bulk_viscosity_limit(h, np.full(4, 20.0), linear=0.5) == pytest.approx(0.125 * 0.01 / 10.0)
    assert bulk_viscosity_limit(h, np.full(4, 20.0), linear=0.0) == np.inf
    a = np.array([[0.0, -9.81]] * 4)
    assert force_limit(h, a) == pytest.approx(0.25 * np.sqrt(0.01 / 9.81))
    assert force_limit(h, np.zeros((4, 2))) == np.inf
    hh, c = np.array([0.01, 0.012]), np.array([20.0, 25.0])
    dt = pair_viscosity_limit(hh, c, alpha=0.1, beta=1.0, max_phi=2.0)
    expected = 0.4 * min(0.01 / (20 + 0.6 * (2.0 + 2.0)), 0.012 / (25 + 0.6 * (2.5 + 2.0)))
    assert dt == pytest.approx(expected, rel=1e-15)
    # a non-finite state gives a NaN limit (the watchdog names the particle), not an exception
    c_bad = np.array([20.0, np.nan])
    assert math.isnan(pair_viscosity_limit(hh, c_bad, 0.1, 0.0, 0.0))
    assert math.isnan(acoustic_limit(hh, c_bad, np.zeros((2, 2))))
    assert all(f(np.zeros(0), *args) == np.inf for f, args in [
        (acoustic_limit, (np.zeros(0), np.zeros((0, 2)))), (pair_viscosity_limit, (np.zeros(0), 0.1, 0.0, 0.0))])
