"""The run checks of the fluid (:mod:`mlsgalerkin.fluid.run_checks`): the time-series columns and
summary entries of the volume, the pair distances, the Mach number and the fallback shares, and
the one warning each past its documented limit."""

from __future__ import annotations

import itertools
import json
import math
import re
import warnings

import numpy as np
import pytest

from mlsgalerkin.fluid import (
    FluidBody,
    Gravity,
    MachNumberWarning,
    MonaghanViscosity,
    ParticleClumpingWarning,
    Phase,
    ShapeFunctionFallbackWarning,
    TaitPressure,
    VolumeErrorWarning,
    Walls,
    run_checks,
    wall_box,
)
from mlsgalerkin.fluid.distribution import AT_FLOOR, NEIGHBOUR_CLASSES
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation

DX = 0.02
WATER = [Phase("water", 1000.0)]
COLUMNS = ("geometric_volume", "volume_error", "min_pair_distance_dx", "clumped_pairs", "min_wall_distance_dx", "mach")


def _tank(water: FluidBody, c0: float = 20.0, t_end: float = 0.02, **scene_kw) -> Scene:
    walls = wall_box((0.0, 0.0), (0.4, 0.4), DX)
    effects = [TaitPressure(c0), Gravity(), Walls(), MonaghanViscosity(0.1)]
    return Scene([water, walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=t_end, **scene_kw)


def _run(scene: Scene, prepare=None):
    sim = Simulation(scene)
    if prepare is not None:
        prepare(sim.state.fluid)   # after the scene's checks (which refuse overlapping particles)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sim.run(progress=False)
    return res, caught


def _warned(caught, category) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category, category)]


def test_a_sound_block_reports_its_volume_and_distribution_without_warning():
    water = FluidBody.block("water", (0.0, 0.0), (0.4, 0.2), DX, WATER)
    res, caught = _run(_tank(water))
    ts = res.timeseries
    for c in COLUMNS:
        assert c in ts, c
    for c in ("kinetic_energy", "max_speed", "fallback_points", "wall_penetrations"):   # kept
        assert c in ts, c
    assert ts["geometric_volume"][0] == pytest.approx(water.n * DX**2, rel=1e-12)
    assert abs(ts["volume_error"][0]) < 1e-12
    assert ts["min_pair_distance_dx"][0] == pytest.approx(1.0) and ts["clumped_pairs"][0] == 0
    assert ts["min_wall_distance_dx"][0] == pytest.approx(1.0)
    assert np.all(np.abs(ts["volume_error"]) < 0.01)
    speed = ts["max_speed"]
    np.testing.assert_allclose(ts["mach"], speed / 20.0, rtol=1e-12)
    rep = res.summary["fluid"]["run_checks"]
    assert rep["volume"]["max_abs_error"] < 0.01 and not rep["volume"]["warned"]
    assert rep["volume"]["error_last"] == pytest.approx(ts["volume_error"][-1])
    assert rep["particle_distribution"]["max_clumped_pairs"] == 0
    assert rep["mach"]["max"] >= ts["mach"].max() and rep["mach"]["c0"] == 20.0 and not rep["mach"]["warned"]
    fb = rep["shape_function_fallback"]
    assert fb["evaluations"] == res.summary["steps"] + 1 and fb["point_share"] == 0.0
    for cat in (VolumeErrorWarning, ParticleClumpingWarning, MachNumberWarning, ShapeFunctionFallbackWarning):
        assert not _warned(caught, cat), cat


def test_a_compressed_block_is_warned_as_lost_volume():
    water = FluidBody.block("water", (0.0, 0.0), (0.4, 0.2), DX, WATER)
    water.positions[:, 1] *= 0.95    # the particles pack 5 % tighter than M/ρ says
    res, caught = _run(_tank(water, t_end=0.005))
    assert res.timeseries["volume_error"][0] == pytest.approx(-0.05 * (9 / 10), abs=0.01)
    rep = res.summary["fluid"]["run_checks"]["volume"]
    assert rep["warned"] and rep["max_abs_error"] > 0.03 and rep["time_of_max_s"] is not None
    msg = _warned(caught, VolumeErrorWarning)
    assert len(msg) == 1 and "lost" in msg[0] and "limit 1%" in msg[0]
    # the warned (and largest) reading split by where it sits: the bulk carries the packing
    where = rep["where_at_max"]
    assert where["time_s"] == rep["time_of_max_s"]
    assert where["volume_error"] == pytest.approx(-rep["max_abs_error"], rel=1e-9)
    parts = [where[name]["contribution"] for name, _, _ in NEIGHBOUR_CLASSES]
    assert sum(parts) == pytest.approx(where["volume_error"], abs=1e-12)
    assert where["surface rows and bulk"]["contribution"] < 0.95 * where["volume_error"]
    assert f"surface rows and bulk {where['surface rows and bulk']['contribution']:+.2%}" in msg[0]


def test_clumped_pairs_are_counted_and_warned_once():
    water = FluidBody.block("water", (0.0, 0.0), (0.4, 0.2), DX, WATER)

    def clump(s):
        s.x[30] = s.x[31] + (0.3 * DX, 0.0)

    res, caught = _run(_tank(water, t_end=0.005), clump)
    assert res.timeseries["clumped_pairs"][0] == 1
    assert res.timeseries["min_pair_distance_dx"][0] == pytest.approx(0.3)
    rep = res.summary["fluid"]["run_checks"]["particle_distribution"]
    assert rep["max_clumped_pairs"] >= 1 and rep["min_pair_distance_dx"] <= 0.3 + 1e-9 and rep["warned"]
    assert rep["time_of_min_s"] is not None and rep["clump_distance_dx"] == 0.5
    assert len(_warned(caught, ParticleClumpingWarning)) == 1


def test_a_fast_flow_is_warned_with_the_sound_speed_to_use():
    water = FluidBody.block("water", (0.05, 0.05), (0.25, 0.15), DX, WATER, velocity=(3.5, 0.0))
    # c0 = 20 m/s against 3.5 m/s: Mach 0.175 > 0.15 from the first step
    res, caught = _run(_tank(water, c0=20.0, t_end=0.005))
    rep = res.summary["fluid"]["run_checks"]["mach"]
    assert rep["max"] > run_checks.MACH_LIMIT and rep["warned"]
    msg = _warned(caught, MachNumberWarning)
    assert len(msg) == 1
    raise_to = float(re.search(r"Raise c0 to at least ([0-9.]+) m/s", msg[0]).group(1))
    assert raise_to == pytest.approx(3.5 / run_checks.MACH_TARGET, rel=0.05)   # the speed then, at Mach 0.1
    assert res.timeseries["mach"][0] == pytest.approx(3.5 / 20.0)


def test_fallback_shares_are_reported_and_warned(monkeypatch):
    # a spray of particles three spacings apart: none has enough neighbours for linear MLS
    monkeypatch.setattr(run_checks, "FALLBACK_MIN_EVALUATIONS", 5)
    spray = FluidBody("spray", np.array([[0.05 + 3 * DX * i, 0.2] for i in range(5)]), DX, WATER)
    res, caught = _run(_tank(spray, t_end=0.004))
    fb = res.summary["fluid"]["run_checks"]["shape_function_fallback"]
    assert fb["evaluation_share"] == 1.0 and fb["point_share"] == pytest.approx(1.0)
    assert fb["warned"] and fb["point_share_limit"] == run_checks.FALLBACK_POINT_SHARE_LIMIT
    assert len(_warned(caught, ShapeFunctionFallbackWarning)) == 1


def test_the_distribution_is_evaluated_at_most_every_few_steps(monkeypatch):
    calls = []
    real = run_checks.volume_error
    monkeypatch.setattr(run_checks, "volume_error", lambda *args: calls.append(1) or real(*args))
    water = FluidBody.block("water", (0.0, 0.0), (0.4, 0.2), DX, WATER)
    res = Simulation(_tank(water, t_end=0.01)).run(progress=False)   # a row every step
    steps = res.summary["steps"]
    assert len(res.timeseries["time"]) == steps + 1
    assert len(calls) == math.ceil((steps + 1) / run_checks.DISTRIBUTION_EVERY_STEPS)


def test_the_checks_state_round_trips():
    a = run_checks.FluidRunChecks()
    a.volume.update(max_abs_error=0.02, time_of_max_s=1.5, warned=True)
    a.pairs.update(min_pair_distance_dx=0.4, max_clumped_pairs=3)
    a.mach.update(max=0.2, warned=True)
    a.fallback.update(evaluations=17)
    a.last.update(step=40, columns={"volume_error": -0.02, "clumped_pairs": 3})
    b = run_checks.FluidRunChecks()
    b.load_state_dict(a.state_dict())
    assert b.state_dict() == a.state_dict()


class _At:
    """The little of a state that the volume record reads: the time."""

    def __init__(self, t: float) -> None:
        self.t = t


def _volume_series(checks, times, errors, split_now=None) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", VolumeErrorWarning)
        for t, e in zip(times, errors):
            checks._record_volume(_At(float(t)), float(e), None if split_now is None else split_now(float(t), float(e)))


def test_the_largest_readings_are_split_from_half_a_percent_in_steps():
    """An error rising to 2 % and falling back: readings are split from 0.5 % on, each at least a
    step past the last split, and the warned one (past 1 %); none while it falls."""
    errors = np.r_[np.linspace(0.0, 0.02, 401), np.linspace(0.02, 0.0, 101)[1:]]
    times = 0.001 * np.arange(errors.size)
    split = []

    def split_now(t, e):
        def where():
            split.append(e)
            return {"time_s": t, "volume_error": e}
        return where

    a = run_checks.FluidRunChecks()
    _volume_series(a, times, errors, split_now)
    step, start = run_checks.VOLUME_ATTRIBUTION_STEP, run_checks.VOLUME_ATTRIBUTION_FROM
    assert min(split) >= start and np.all(np.diff(split) > 0)
    warned = errors[errors > run_checks.VOLUME_ERROR_LIMIT][0]
    assert warned in split
    assert all(later - earlier >= step - 1e-15 for earlier, later in itertools.pairwise(split) if later != warned)
    assert len(split) <= (0.02 - start) / step + 2
    assert a.volume["where_at_max"]["volume_error"] == split[-1] >= 0.02 - step


def test_the_running_mean_sees_past_one_scattered_reading():
    """A steady 0.6 % with one reading of 1.6 %: the largest reading is 1.6 %, the largest 50 ms
    mean stays near 0.6 %; a 2 % plateau 0.1 s long is the mean's too."""
    times = np.arange(0.0, 1.0, 0.002)
    errors = np.full(times.size, 0.006)
    errors[200] = 0.016
    a = run_checks.FluidRunChecks()
    _volume_series(a, times, errors)
    assert a.volume["max_abs_error"] == pytest.approx(0.016)
    assert a.volume["max_abs_mean_error"] == pytest.approx(0.006 + 0.01 / 25, rel=1e-9)   # 25 readings a window
    assert times[200] <= a.volume["time_of_max_mean_s"] < times[200] + run_checks.VOLUME_MEAN_WINDOW
    errors[300:350] = 0.02
    b = run_checks.FluidRunChecks()
    _volume_series(b, times, errors)
    assert b.volume["max_abs_mean_error"] == pytest.approx(0.02)
    # no mean before a whole window has been evaluated
    c = run_checks.FluidRunChecks()
    _volume_series(c, times[:20], errors[:20])
    assert c.volume["max_abs_mean_error"] is None


def test_the_running_mean_survives_a_restart():
    times = np.arange(0.0, 0.4, 0.002)
    errors = 0.01 * np.sin(37.0 * times) + 0.003 * np.cos(411.0 * times)
    whole = run_checks.FluidRunChecks()
    _volume_series(whole, times, errors)
    first = run_checks.FluidRunChecks()
    _volume_series(first, times[:91], errors[:91])
    second = run_checks.FluidRunChecks()
    second.load_state_dict(json.loads(json.dumps(first.state_dict())))   # as a checkpoint stores it
    _volume_series(second, times[91:], errors[91:])
    assert second.volume == whole.volume


def test_a_gain_at_the_cavitation_floor_is_named_in_the_warning():
    """A gain that the particles at p ≤ 0 carry: the warning says where it sits and does not
    advise cavitation (the run has it); a gain in the bulk keeps the general advice."""
    def split(floor):
        return lambda: {"time_s": 0.3, "volume_error": 0.012, "drops": {"particles": 0.0, "contribution": 0.0},
                        "sheets and ragged surface": {"particles": 0.2, "contribution": 0.011},
                        "surface rows and bulk": {"particles": 0.8, "contribution": 0.001},
                        AT_FLOOR: {"particles": 0.25, "contribution": floor}}
    for floor, expected, absent in ((0.015, "Most of it sits at the cavitation floor", "Try cavitation"),
                                    (0.001, "Try cavitation", "Most of it sits")):
        checks = run_checks.FluidRunChecks()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            checks._record_volume(_At(0.3), 0.012, split(floor))
        msg = _warned(caught, VolumeErrorWarning)
        assert len(msg) == 1 and expected in msg[0] and absent not in msg[0]
        assert f"sheets and ragged surface +1.10%, surface rows and bulk +0.10%; {AT_FLOOR} (p ≤ 0) {floor:+.2%}" in msg[0]
        assert checks.volume["where_at_max"]["volume_error"] == 0.012

