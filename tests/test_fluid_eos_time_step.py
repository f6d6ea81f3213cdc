"""Tait equation of state and the explicit time-step limits."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.fluid import MachNumberWarning, TaitEOS, acoustic_limit, force_limit, viscous_limit


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


def test_time_step_limits():
    h = np.full(4, 0.01)
    v = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, -2.0], [0.0, 0.0]])
    assert acoustic_limit(h, 20.0, v) == pytest.approx(0.4 * 0.01 / 22.0)
    assert viscous_limit(h, 1e-6) == pytest.approx(0.125 * 1e-4 / 1e-6)
    assert viscous_limit(h, 0.0) == np.inf
    a = np.array([[0.0, -9.81]] * 4)
    assert force_limit(h, a) == pytest.approx(0.25 * np.sqrt(0.01 / 9.81))
    assert force_limit(h, np.zeros((4, 2))) == np.inf
    with pytest.raises(ValueError, match="not finite at particle 2"):
        force_limit(h, np.array([[0, 0], [0, 0], [np.nan, 0], [0, 0]], dtype=float))
    with pytest.raises(ValueError, match="h must be positive"):
        acoustic_limit(np.array([0.01, 0.0]), 20.0)
