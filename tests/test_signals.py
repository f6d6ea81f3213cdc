"""Signal analysis (mlsgalerkin.analysis.signals) on signals whose answer is known."""

import math

import numpy as np
import pytest

from mlsgalerkin.analysis.signals import (
    crossing_period,
    grid_average,
    half_height_window,
    running_mean,
    spectral_period,
    threshold_windows,
    upward_crossings,
)


def test_upward_crossings_of_a_sine_are_its_period_starts():
    t = np.linspace(0.0, 1.0, 1001)
    y = np.sin(2 * math.pi * (t - 0.05) / 0.25)   # upward zeros at 0.05 + k 0.25
    tc = upward_crossings(t, y)
    np.testing.assert_allclose(tc, [0.05, 0.30, 0.55, 0.80], atol=1e-6)
    line = 2.0 * (t - 0.4321)                       # linear: the interpolation is exact
    assert upward_crossings(t, line) == pytest.approx([0.4321], abs=1e-14)
    assert upward_crossings(t, -line).size == 0     # downward only


def test_crossing_period_is_measured_about_the_mean_and_counts_periods():
    t = np.linspace(0.0, 3.0, 30001)
    period, cycles = crossing_period(t, 5.0 + 0.1 * np.sin(2 * math.pi * t / 0.6))
    assert period == pytest.approx(0.6, abs=1e-6) and cycles == 4
    assert crossing_period(t[:2], t[:2]) == (pytest.approx(math.nan, nan_ok=True), 0)
    p, n = crossing_period(t, t)                    # no oscillation: not measured
    assert math.isnan(p) and n == 0


@pytest.mark.parametrize("true_period", [0.37, 0.6, 1.1])
def test_spectral_period_finds_the_peak_within_a_band(true_period):
    t = np.sort(np.random.default_rng(1).uniform(0.0, 6.0, 3000))   # uneven samples
    y = 0.3 * t + np.sin(2 * math.pi * t / true_period) + 0.3 * np.sin(2 * math.pi * t / 0.05)
    refined = spectral_period(t, y, hann=True, pad=8, band=(0.3, 1.5), refine=True)
    assert refined == pytest.approx(true_period, rel=5e-3)
    # no band: the strongest of all (the 0.05 s tone is weaker); bins of 1/6 Hz limit the accuracy
    coarse = spectral_period(t, y, samples=1024, detrend=2, hann=False)
    assert coarse == pytest.approx(true_period, rel=0.2)
    assert math.isnan(spectral_period(t, y, band=(5.0, 6.0)))      # fewer than three bins in the band


def test_running_mean_of_a_line_is_the_line_inside_and_of_one_period_is_the_mean():
    t = np.linspace(0.0, 2.0, 2001)
    m = running_mean(t, 3.0 * t + 1.0, 0.1005)   # 101 samples, symmetric about each
    inner = (t > 0.06) & (t < 1.94)
    np.testing.assert_allclose(m[inner], 3.0 * t[inner] + 1.0, atol=1e-12)
    m = running_mean(t, 2.0 + np.sin(2 * math.pi * t / 0.2), 0.2)
    inner = (t > 0.11) & (t < 1.89)                   # whole windows only
    assert np.abs(m[inner] - 2.0).max() < 5e-3        # 200 or 201 samples over one period


def test_grid_average_resamples_and_keeps_a_constant():
    t = np.array([0.0, 0.0105, 0.02, 0.0333, 0.05])
    grid, mean = grid_average(t, np.full(5, 7.0), span=0.01, step=1e-3)
    assert grid[0] == 0.0 and grid[-1] == pytest.approx(0.05) and grid.size == 51
    np.testing.assert_allclose(mean, 7.0, rtol=0, atol=1e-12)


def test_threshold_windows_merge_short_gaps_only():
    t = np.arange(0.0, 10.0, 0.1)
    y = np.zeros_like(t)
    y[(t > 1.0) & (t < 2.0)] = -5.0   # |y| counts
    y[(t > 2.2) & (t < 2.5)] = 5.0    # 0.3 s after: merged with gap 0.5
    y[(t > 6.0) & (t < 6.3)] = 5.0    # far: its own window
    got = threshold_windows(t, y, 1.0, gap=0.5)
    assert got == [pytest.approx((1.1, 2.4)), pytest.approx((6.1, 6.2))]
    assert threshold_windows(t, y, 1.0, gap=0.15)[:2] == [pytest.approx((1.1, 1.9)), pytest.approx((2.3, 2.4))]
    assert threshold_windows(t, y, 10.0) == []


def test_half_height_window_of_a_gaussian_is_sigma_sqrt_ln4_wide():
    t = np.arange(0.0, 4.0, 1e-3)
    sigma = 0.25
    y = 245.0 + 1800.0 * np.exp(-((t - 1.5) / sigma) ** 2)
    a, b = half_height_window(y, int(np.argmax(y)), 245.0)
    half = sigma * math.sqrt(math.log(2.0))
    assert (t[a], t[b]) == (pytest.approx(1.5 - half, abs=1e-3), pytest.approx(1.5 + half, abs=1e-3))
