"""The channel profile analysis: row means, the three-row filter and the split of a profile's
deviation into a smooth part and a row-to-row alternation (``mlsgalerkin.analysis.channel``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mlsgalerkin.analysis.channel import ChannelProfileErrors, channel_profile_errors, row_means, three_row_filter
from mlsgalerkin.problem import load_problem

K = 11                                   # rows (odd: one row at mid-height)
H = 1.0                                  # channel height (m)
U = 2.0                                  # speed scale (m/s)
Y = (np.arange(K) + 0.5) * H / K         # row heights (m)
EXACT = 4.0 * U * Y * (H - Y)            # a parabola (m/s)
SLOPE = 0.003                            # smooth error per row (m/s)
ALTERNATION = 0.02                       # row-to-row alternation (m/s)


def profile() -> np.ndarray:
    """The exact profile plus a smooth error linear in the row index plus an alternation."""
    k = np.arange(K)
    return EXACT + SLOPE * k + ALTERNATION * (-1.0) ** k


def test_the_filter_removes_an_alternation_and_keeps_a_linear_profile():
    k = np.arange(9, dtype=float)
    np.testing.assert_allclose(three_row_filter((-1.0) ** k), 0.0, atol=1e-15)
    np.testing.assert_allclose(three_row_filter(3.0 + 0.5 * k), 3.0 + 0.5 * k[1:-1], rtol=1e-15)
    # and weights ¼ ½ ¼, not a plain mean of three
    assert three_row_filter(np.array([0.0, 4.0, 0.0])) == pytest.approx([2.0])


def test_a_known_smooth_error_and_alternation_are_split_apart():
    e = channel_profile_errors(Y, profile(), EXACT, scale=U, height=H)
    k = np.arange(K)
    dev = (SLOPE * k + ALTERNATION * (-1.0) ** k) / U
    assert e.max == pytest.approx(np.max(np.abs(dev)), rel=1e-12)
    assert e.rms == pytest.approx(np.sqrt(np.mean(dev**2)), rel=1e-12)
    # the filter passes the linear error untouched and removes the alternation: the smooth part is
    # the linear error over the inner rows, the alternation its amplitude
    assert e.max_smooth == pytest.approx(SLOPE * (K - 2) / U, rel=1e-10)
    assert e.alternation == pytest.approx(ALTERNATION / U, rel=1e-10)
    # the row at mid-height
    assert e.centre_speed == profile()[K // 2]
    assert e.centre_speed_exact == EXACT[K // 2]
    assert e.rows == K


def test_no_alternation_and_no_smooth_error_are_told_apart():
    k = np.arange(K)
    only_alternation = channel_profile_errors(Y, EXACT + ALTERNATION * (-1.0) ** k, EXACT, scale=U, height=H)
    assert only_alternation.max_smooth < 1e-12
    assert only_alternation.alternation == pytest.approx(ALTERNATION / U, rel=1e-10)
    only_smooth = channel_profile_errors(Y, EXACT + SLOPE * k, EXACT, scale=U, height=H)
    assert only_smooth.alternation < 1e-12
    assert only_smooth.max_smooth == pytest.approx(SLOPE * (K - 2) / U, rel=1e-10)


def test_results_and_headline_keep_the_problems_keys_and_wording():
    e = ChannelProfileErrors(max=0.0123, rms=0.0045, max_smooth=0.0067, alternation=0.0089, centre_speed=1.5,
                             centre_speed_exact=1.49, rows=20)
    assert list(e.results()) == ["profile_error_max", "profile_error_rms", "profile_error_max_smooth",
                                 "row_alternation_amplitude", "centre_speed_m_s", "centre_speed_exact_m_s"]
    assert e.results()["row_alternation_amplitude"] == 0.0089
    assert e.headline("u_max", 0.5, 0.434, 10.0) == (
        "velocity profile within 1.23 % of u_max of the start-up series at t = 0.5 s (RMS 0.45 %; the flow at "
        "43 % of steady); smooth part within 0.67 %, row-to-row alternation 0.89 %; Re = 10")


def test_row_means_average_each_lattice_row_and_skip_empty_ones():
    dx, height = 0.25, 1.0
    y = np.array([0.1, 0.2, 0.3, 0.4, 0.9, 0.95, 1.02])   # row 2 empty; 1.02 joins the top row
    u = np.array([1.0, 3.0, 5.0, 7.0, 2.0, 4.0, 6.0])
    ym, um = row_means(y, u, height, dx)
    np.testing.assert_allclose(ym, [0.15, 0.35, (0.9 + 0.95 + 1.02) / 3])
    np.testing.assert_allclose(um, [2.0, 6.0, 4.0])


def test_a_profile_too_short_or_of_mismatched_shapes_is_refused():
    with pytest.raises(ValueError, match="at least 3 rows"):
        channel_profile_errors(Y[:2], EXACT[:2], EXACT[:2], scale=U, height=H)
    with pytest.raises(ValueError, match="one length"):
        channel_profile_errors(Y, EXACT[:-1], EXACT, scale=U, height=H)


@pytest.mark.parametrize("name", ["couette", "poiseuille"])
def test_the_problems_forward_their_old_filter_name_with_a_warning(name):
    module = load_problem(name)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        forwarded = module.three_row_filter
    assert forwarded is three_row_filter
    assert any(issubclass(w.category, DeprecationWarning) and "mlsgalerkin.analysis.channel" in str(w.message)
               for w in caught)
