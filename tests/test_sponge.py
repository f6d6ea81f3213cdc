"""The sponge zone (mlsgalerkin.fluid.sponge): it damps the velocity inside the zone at the
rate it states, leaves the fluid outside alone, and takes energy out of a sloshing tank."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mlsgalerkin.fluid import FluidBody, Phase, TaitPressure
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.fluid.sponge import SpongeZone, sponge_rate
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation
from verification.sloshing_energy import sloshing_scene


def test_rate_profile():
    x = np.array([[0.0, 0.0], [1.0, 0.0], [1.5, 0.0], [2.0, 0.0], [3.0, 0.0]])
    np.testing.assert_allclose(sponge_rate(x, 1.0, 1.0, 0, 1.0, 8.0), [0, 0, 2.0, 8.0, 8.0])
    np.testing.assert_allclose(sponge_rate(x, 1.0, 1.0, 0, -1.0, 8.0), [8.0, 0, 0, 0, 0])


def test_damps_inside_the_zone_only():
    # a free block moving at 1 m/s, no pressure gradients: the particles beyond the full-strength
    # end of the zone decay as exp(−rate t), the ones before its start keep their speed
    fl = FluidBody.block("water", (0.0, 0.0), (0.4, 0.1), 0.02, [Phase("water", 1000.0)], velocity=(0.0, 1.0))
    rate, t_end = 5.0, 0.1
    scene = Scene([fl], [FluidScheme([TaitPressure(20.0), SpongeZone(0.1, 0.1, rate)], stabilisation="as_listed")], t_end=t_end)
    res = Simulation(scene).run(progress=False)
    s = res.state.fluid
    x0 = fl.positions[:, 0]
    deep, outside = x0 > 0.25, x0 < 0.08
    np.testing.assert_allclose(s.v[:fl.n][deep, 1], math.exp(-rate * t_end), rtol=0.02)
    # outside the zone only the pressure waves from the slowed part arrive: measured within
    # 3.7e-4 of 1 m/s (the zone itself took 39 % of the speed)
    np.testing.assert_allclose(s.v[:fl.n][outside, 1], 1.0, atol=2e-3)


def test_takes_energy_out_of_a_sloshing_tank():
    """The energy of the motion, kinetic + potential + compression above the rest state the run
    starts from (``E(t) − (E(0) − K(0))``), at 0.5 s (under half a sloshing period): measured
    0.674 J/m with the zone against 0.778 J/m without it (0.87; 0.84 before the droplets and 0.82
    without the linear consistency). The kinetic energy alone swings with the acoustic waves the
    initial flow's compression sends (0.03 to 0.3 J/m within 0.1 s), so one sample of it says
    little. The volume consistency's loose side is left out of both runs: at these 10 rows the
    sloshing surface reads volume errors up to 0.97 %, past its 0.5 % band, and its relaxation
    lets the packing settle, which lowers the rest state's potential energy (0.685 J/m at 0.5 s
    without the zone; 0.662 with it) and would blur the zone's share; it does not damp the wave
    (``verification/sloshing_energy.py``, ``docs/theory/stabilisation.md`` §10)."""
    def motion_energy(extra):
        scene = sloshing_scene(0.015, loose_band=0.0, t_end=0.5, extra=extra)
        ts = Simulation(scene).run(progress=False).timeseries
        energy = (np.asarray(ts["kinetic_energy"]) + np.asarray(ts["potential_energy"])
                  + np.asarray(ts["compression_energy"]))
        return energy[-1] - (energy[0] - ts["kinetic_energy"][0])
    plain = motion_energy([])
    sponged = motion_energy([SpongeZone(0.4, 0.15, 10.0)])
    assert 0.0 < sponged < 0.9 * plain


def test_bad_zone_is_refused():
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, 0.2), 0.02, [Phase("water", 1000.0)])
    scene = Scene([fl], [FluidScheme([TaitPressure(20.0), SpongeZone(0.1, 0.0, -1.0, axis=3)], stabilisation="as_listed")], t_end=0.1)
    with pytest.raises(ValueError) as err:
        Simulation(scene)
    text = str(err.value)
    assert "rate" in text and "length" in text and "axis" in text
