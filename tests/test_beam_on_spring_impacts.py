"""How ``beam_on_spring`` finds the water's impacts on the beam, on signals with known answers:
the centre of mass from the momentum, the running mean, the impacts and their windows."""

import math

import numpy as np
import pytest

from mlsgalerkin.problem import load_problem

spring = load_problem("beam_on_spring")


def test_centre_of_mass_is_the_time_integral_of_the_momentum():
    """``x_G = x0 + ∫ P/M dt``: exact for a momentum linear in time (the trapezoidal rule), and
    within O(Δt²) for ``P = M A ω cos ωt``, whose centre is ``x0 + A sin ωt``."""
    t = np.linspace(0.0, 2.0, 2001)
    x = spring.water_centre_x(t, 3.0 + 4.0 * t, 10.0, 0.6)
    np.testing.assert_allclose(x, 0.6 + (3.0 * t + 2.0 * t ** 2) / 10.0, rtol=0, atol=1e-14)
    w, a = 2 * math.pi / 4.4, 0.7
    x = spring.water_centre_x(t, 720.0 * a * w * np.cos(w * t), 720.0, 1.2)
    np.testing.assert_allclose(x, 1.2 + a * np.sin(w * t), rtol=0, atol=1e-6)


def test_the_running_mean_removes_one_period_and_a_splash_spike():
    """Averaged over one period, a sinusoid of that period leaves its mean; a 5 ms spike of
    30 kPa leaves at most 30 kPa · 5/200."""
    t = np.arange(0.0, 3.0, 1e-3)
    y = 500.0 + 200.0 * np.sin(2 * math.pi * t / 0.2)
    y[1500:1505] += 30e3
    grid, mean = spring.averaged(t, y, 0.2)
    inner = (grid > 0.2) & (grid < 2.8)
    assert np.abs(mean[inner] - 500.0).max() <= 30e3 * 5 / 200 + 5.0


def _sloshing(second_at=5.3, wiggle=0.02):
    """A centre of mass with a big first swing, a small wiggle and a smaller return; a load with a
    Gaussian peak before each maximum and a rest value of 245 N/m."""
    t = np.arange(0.0, 7.0, 1e-3)
    centre = (1.61 + 0.4 * np.exp(-((t - 1.7) / 0.5) ** 2) - 0.15 * np.exp(-((t - 3.5) / 0.6) ** 2)
              + wiggle * np.exp(-((t - 2.7) / 0.1) ** 2) + 0.08 * np.exp(-((t - second_at) / 0.5) ** 2))
    centre[t < 0.5] = 0.6 + (centre[t < 0.5][-1] - 0.6) * t[t < 0.5] / 0.5
    load = (245.0 + 1800.0 * np.exp(-((t - 1.55) / 0.25) ** 2)
            + 300.0 * np.exp(-((t - (second_at - 0.2)) / 0.3) ** 2))
    return t, centre, load


def test_impacts_are_the_swings_of_the_water_towards_the_beam():
    t, centre, load = _sloshing()
    found = spring.impacts(t, centre, load, 245.0)
    assert [round(i["centre_max_s"], 2) for i in found] == [1.7, 5.3]
    assert [round(i["load_peak_s"], 2) for i in found] == [1.55, 5.1]
    # the window is where the load exceeds rest + half the excess: ± σ sqrt(ln 2) for a Gaussian
    for item, (mid, sigma) in zip(found, ((1.55, 0.25), (5.1, 0.3))):
        half = sigma * math.sqrt(math.log(2.0))
        assert item["window_s"] == pytest.approx([mid - half, mid + half], abs=2e-3)


def test_a_wiggle_of_the_water_is_not_an_impact_but_a_real_swing_is():
    t, centre, load = _sloshing(wiggle=0.5 * spring.SLOSH_PROMINENCE)
    assert len(spring.impacts(t, centre, load, 245.0)) == 2
    t, centre, load = _sloshing(wiggle=3.0 * spring.SLOSH_PROMINENCE)
    assert [round(i["centre_max_s"], 1) for i in spring.impacts(t, centre, load, 245.0)] == [1.7, 2.7, 5.3]


def test_offset_from_a_window():
    assert spring.outside(5.3, (5.1, 5.9)) == 0.0
    assert spring.outside(4.85, (5.1, 5.9)) == pytest.approx(-0.25)
    assert spring.outside(6.0, (5.1, 5.9)) == pytest.approx(0.1)


def test_the_late_period_is_read_about_the_drifting_lean():
    # after 6 s the lean drifts by a degree while the beam swings by 0.3 degrees at 0.2 s (the
    # default run at 15 mm): the angle crosses its own mean once, its running mean every period
    t = np.arange(6.0, 7.0, 1e-3)
    theta = np.radians(-0.5 - 0.9 * (t - 6.0) + 0.3 * np.sin(2 * math.pi * t / 0.2))
    from mlsgalerkin.analysis.signals import crossing_period
    assert crossing_period(t, theta)[1] < 2
    period, periods = spring.late_period(t, theta)
    assert period == pytest.approx(0.2, rel=0.01) and periods == 3      # read on [6.1, 6.9] s
