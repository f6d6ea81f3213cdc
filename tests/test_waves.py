"""Incident and reflected waves split from gauge records (``mlsgalerkin.analysis.waves``), and the
wave maker's gauges and reflection coefficient built on it."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.analysis.waves import (
    complex_amplitude,
    gauge_positions,
    harmonic_fit,
    incident_reflected,
)

K = 2 * math.pi / 1.2     # a 1.2 m wave
OMEGA = 2 * math.pi       # of 1 s period
T = np.linspace(2.0, 10.0, 801)


def _records(x, a_i, a_r, phase_r, mean=0.0, second=0.0):
    """Gauge records of an incident wave ``a_i cos(ωt − kx)`` and a reflected one
    ``a_r cos(ωt + kx + phase_r)``, with a mean level and a bound second harmonic."""
    return [mean + a_i * np.cos(OMEGA * T - K * xj) + a_r * np.cos(OMEGA * T + K * xj + phase_r)
            + second * np.cos(2 * (OMEGA * T - K * xj)) for xj in x]


@settings(max_examples=40, deadline=None)
@given(a_i=st.floats(0.001, 0.05), kr=st.floats(0.0, 1.0), phase=st.floats(-math.pi, math.pi),
       x1=st.floats(0.5, 3.0), mean=st.floats(-0.01, 0.01), second=st.floats(0.0, 0.003))
def test_the_split_recovers_both_waves_of_a_synthetic_record(a_i, kr, phase, x1, mean, second):
    x = gauge_positions(x1, 1.2)
    split = incident_reflected(x, [complex_amplitude(T, r, OMEGA) for r in _records(x, a_i, kr * a_i, phase, mean,
                                                                                    second)], K)
    assert abs(split.incident) == pytest.approx(a_i, rel=1e-9)
    assert abs(split.reflected) == pytest.approx(kr * a_i, abs=1e-9 * a_i)
    assert split.reflection_coefficient == pytest.approx(kr, abs=1e-9)
    assert split.relative_misfit < 1e-9


def test_a_standing_wave_reflects_fully_and_a_progressive_one_not_at_all():
    x = gauge_positions(1.0, 1.2)
    standing = incident_reflected(x, [complex_amplitude(T, r, OMEGA) for r in _records(x, 0.01, 0.01, 0.0)], K)
    progressive = incident_reflected(x, [complex_amplitude(T, r, OMEGA) for r in _records(x, 0.01, 0.0, 0.0)], K)
    assert standing.reflection_coefficient == pytest.approx(1.0, abs=1e-9)
    assert progressive.reflection_coefficient == pytest.approx(0.0, abs=1e-9)


def test_two_gauges_are_the_method_of_goda_and_suzuki_and_noise_shows_in_the_misfit():
    x2 = np.array([1.0, 1.3])
    two = incident_reflected(x2, [complex_amplitude(T, r, OMEGA) for r in _records(x2, 0.01, 0.003, 0.7)], K)
    assert two.reflection_coefficient == pytest.approx(0.3, abs=1e-9)
    x3 = gauge_positions(1.0, 1.2)
    records = _records(x3, 0.01, 0.003, 0.7)
    records[1] = records[1] + 0.001 * np.cos(OMEGA * T + 1.0)   # one gauge off by 10 % of the amplitude
    noisy = incident_reflected(x3, [complex_amplitude(T, r, OMEGA) for r in records], K)
    assert noisy.relative_misfit > 0.01


def test_gauges_half_a_wavelength_apart_cannot_split_the_waves():
    with pytest.raises(ValueError, match="cannot separate"):
        incident_reflected([1.0, 1.6], [0.01 + 0j, -0.01 + 0j], K)
    with pytest.raises(ValueError, match="two or more gauge"):
        incident_reflected([1.0], [0.01 + 0j], K)


def test_gauge_positions_follow_mansard_and_funke():
    x = gauge_positions(2.0, 1.2)
    assert np.allclose(np.diff(x), [0.12, 0.18])
    assert x[0] == pytest.approx(2.0 - 0.15)


def test_complex_amplitude_is_the_first_harmonic_of_the_fit():
    eta = 0.002 + 0.01 * np.cos(OMEGA * T - 0.4)
    coef, resid = harmonic_fit(T, eta, OMEGA)
    assert complex_amplitude(T, eta, OMEGA) == pytest.approx(0.01 * np.exp(-0.4j), abs=1e-12)
    assert coef[0] == pytest.approx(0.002) and np.abs(resid).max() < 1e-12


def test_the_wave_maker_places_its_gauges_between_probe_and_sponge_or_leaves_them_out():
    from mlsgalerkin.problems import wave_maker as wm

    p = wm.Parameters(tank_length=3.0, sponge_length=1.2)
    x = wm.reflection_gauges(p)
    assert x.size == 3 and x[0] - p.probe_x >= 2 * p.depth and 1.8 - x[-1] >= 2 * p.depth
    scene = wm.make_scene(wm.Parameters(**wm.SMOKE, sponge_length=0.0))
    names = [probe.name for probe in scene.probes]
    assert names[:2] == ["eta", "piston_x"]
    short = wm.Parameters(tank_length=1.4, sponge_length=0.4)
    assert wm.reflection_gauges(short).size == 0
    assert not any(n.startswith("eta_gauge") for n in [pr.name for pr in wm.make_scene(short).probes])


def test_the_wave_maker_measures_the_reflection_of_a_synthetic_record_and_says_when_it_cannot():
    from mlsgalerkin.problems import wave_maker as wm

    p = wm.Parameters(tank_length=4.2, sponge_length=1.2, ramp_periods=1.0, t_end=11.6)
    k = wm.wave_number(p.period, p.depth, p.g)
    omega = 2 * math.pi / p.period
    t = np.arange(0.0, p.t_end, 0.01)
    gauges = [0.01 * np.cos(omega * t - k * xj) + 0.002 * np.cos(omega * t + k * xj) for xj in wm.reflection_gauges(p)]
    t_from, t_to = wm.reflection_window(p)
    assert t_to - t_from > 2 * p.period and t_to <= p.t_end
    out = wm.end_reflection(t, gauges, p)
    assert out["reflection_coefficient"] == pytest.approx(0.2, abs=1e-6)
    assert out["reflection_coefficient_min"] <= out["reflection_coefficient"] <= out["reflection_coefficient_max"]
    assert out["incident_height_m"] == pytest.approx(0.02, rel=1e-6)
    early = wm.end_reflection(t[t < 9.0], [g[t < 9.0] for g in gauges], p)
    assert early["reflection_coefficient"] is None and "before two periods" in early["reflection_coefficient_not_measured"]
    assert wm.end_reflection(t, [], p)["reflection_coefficient"] is None
    short = wm.Parameters(tank_length=3.0, sponge_length=1.2, t_end=12.0)   # gauges 1.1-1.4 m from the paddle
    close = wm.end_reflection(t, gauges, short)
    assert close["reflection_coefficient"] is None and "lengthen the tank" in close["reflection_coefficient_not_measured"]


def test_the_sponges_round_trip_attenuation_depends_on_rate_times_length_over_group_velocity():
    from mlsgalerkin.problems import wave_maker as wm

    a = wm.sponge_round_trip_attenuation(wm.Parameters(sponge_length=0.6, sponge_rate=10.0))
    b = wm.sponge_round_trip_attenuation(wm.Parameters(sponge_length=1.2, sponge_rate=5.0))
    c = wm.sponge_round_trip_attenuation(wm.Parameters(sponge_length=1.2, sponge_rate=10.0))
    assert a == pytest.approx(b) and c == pytest.approx(a * a)
    cg = wm.group_velocity(1.0, 0.2)
    assert c == pytest.approx(math.exp(-10.0 * 1.2 / (3 * cg)))
