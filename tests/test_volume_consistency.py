"""The density relaxed towards the particles' packing (mlsgalerkin.fluid.volume_consistency):
a fluid packed tighter than its volumes say re-expands, a lattice is left alone, the compiled
kernel agrees with its numpy reference, and bad settings are refused before step 1."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.fluid import FluidBody, Phase, hydrostatic_density, wall_box, water
from mlsgalerkin.fluid.closed_volume import ClosedVolume
from mlsgalerkin.fluid.volume_consistency import (
    VolumeConsistency,
    deep_particles,
    deep_particles_reference,
    disorder_bias_coefficient,
    droplets,
    lattice_shepard_sum,
    loose_particles,
    wall_rows,
    wall_rows_reference,
)
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation

# the squeezed tanks start packed tighter than their volumes say, which the run checks report
pytestmark = pytest.mark.filterwarnings("ignore::mlsgalerkin.fluid.run_checks.VolumeErrorWarning",
                                        "ignore::mlsgalerkin.fluid.run_checks.ParticleClumpingWarning")

G, RHO, DX, DEPTH = 9.81, 1000.0, 0.02, 0.2
C0 = 10 * math.sqrt(2 * G * DEPTH)


def packed_tank(squeeze: float, effect: VolumeConsistency | None, steps: int | None = None, t_end: float = 1.0):
    """A 0.4 m × 0.2 m tank whose water block was squeezed by ``squeeze`` towards the floor and the
    left wall after its masses were set (so it is packed ``1/squeeze²`` tighter than its volumes
    ``M/ρ`` say), at hydrostatic densities of its new heights; run ``steps`` steps or to ``t_end``.
    Returns the simulation and its result."""
    fl = FluidBody.block("water", (0.0, 0.0), (0.4, DEPTH), DX, [Phase("water", RHO)])
    fl.positions[:] *= squeeze
    top = DEPTH * squeeze
    fl.density[:] = hydrostatic_density(np.full(fl.n, RHO), top - fl.positions[:, 1], G, C0)
    walls = wall_box((0.0, 0.0), (0.4, 0.3), DX, layers=3, reference_density=RHO)
    extra = [effect] if effect is not None else []
    scheme = water(C0, spacing=DX, volume_consistency=0.0, extra=extra)
    sim = Simulation(Scene([fl, walls], [scheme], t_end=t_end))
    return sim, sim.run(max_steps=steps, progress=False)


def test_lattice_sums():
    # the square lattice's Shepard sum is 1 to the quadrature error of the kernel
    assert lattice_shepard_sum("cubic_spline", 1.3, 2) == pytest.approx(1.0, abs=1e-4)
    assert lattice_shepard_sum("quintic_spline", 1.3, 3) == pytest.approx(1.0, abs=1e-3)
    assert lattice_shepard_sum("lucy_quartic", 1.3, 2) > 1.05      # a coarse kernel's sum is not 1


def test_the_disorder_bias_is_taken_out():
    # the jittered lattice's sum reads tighter than its volumes by k var(c): k = 3.4-3.7 (2D, cubic spline)
    assert 3.3 < disorder_bias_coefficient("cubic_spline", 1.3, 2) < 4.0
    assert 4.8 < disorder_bias_coefficient("cubic_spline", 1.3, 3) < 5.8
    # a 1 m × 0.5 m tank at rest jittered by ± 0.15 Δx: its raw gap (about 0.6 %) is disorder, and
    # the term stays idle
    eff = VolumeConsistency()
    fl = FluidBody.block("water", (0.0, 0.0), (1.0, 0.5), DX, [Phase("water", RHO)])
    fl.positions[:] += np.random.default_rng(7).uniform(-0.15, 0.15, fl.positions.shape) * DX
    fl.density[:] = hydrostatic_density(np.full(fl.n, RHO), 0.5 - fl.positions[:, 1], G, C0)
    walls = wall_box((0.0, 0.0), (1.0, 0.6), DX, layers=3, reference_density=RHO)
    sim = Simulation(Scene([fl, walls], [water(C0, spacing=DX, volume_consistency=0.0, extra=[eff])], t_end=1.0))
    sim.run(max_steps=1, progress=False)
    s = sim.state.fluid
    deep = deep_particles(s.table, s.table.kernel_sum, s.n_fluid, eff.surface * eff.reference)
    raw = s.table.kernel_sum[: s.n_fluid][deep].mean() / eff.reference - 1.0
    assert raw > 0.004 and abs(eff.gap_mean) < 0.5 * eff.band and eff.active_evaluations == 0


def test_a_lattice_is_left_alone_and_a_packed_fluid_gains_density():
    rest = VolumeConsistency()
    packed_tank(1.0, rest, steps=1)
    assert abs(rest.gap_mean) < 1e-4                     # the lattice: measured 2e-8
    packed = VolumeConsistency()
    sim, _ = packed_tank(0.95, packed, steps=1)
    assert packed.gap_mean == pytest.approx(1 / 0.95**2 - 1, rel=0.02)    # 10.8 %
    s = sim.state.fluid
    deep = deep_particles(s.table, s.table.kernel_sum, s.n_fluid, packed.surface * packed.reference)
    x, y = s.x[: s.n_fluid, 0], s.x[: s.n_fluid, 1]
    assert deep.any() and not deep[y > 0.95 * DEPTH - 2 * DX].any()     # the top two rows are not deep
    assert not deep[(x < 2 * DX) | (y < 2 * DX)].any()                  # nor the rows that reach a wall
    assert deep[(y > 4 * DX) & (y < 0.95 * DEPTH - 3 * DX) & (x > 4 * DX) & (x < 0.95 * 0.4 - 3 * DX)].all()


def test_a_packed_fluid_re_expands_and_without_the_effect_it_does_not():
    # rate 0.05: a relaxation time of 20 h/c0 = 26 ms, so the test is short
    on = VolumeConsistency(0.05)
    packed_tank(0.95, on, t_end=0.12)
    off = VolumeConsistency(1e-9)                       # listed for its diagnostics, no relaxation
    packed_tank(0.95, off, t_end=0.12)
    assert off.gap_mean > 0.09                           # the packing stays: the continuity does not see it
    assert abs(on.gap_mean) < 0.03                       # measured 0.43 % at 0.12 s, inside the band
    assert on.gap_mean_largest == pytest.approx(off.gap_mean_largest, rel=0.02)


def test_inside_the_band_the_run_is_the_run_without_the_effect():
    # a lattice's gap is 0 to 1e-3, inside the default band (0.4 %): not a bit changes
    eff = VolumeConsistency()
    a = packed_tank(1.0, eff, steps=40)[1].timeseries
    b = packed_tank(1.0, None, steps=40)[1].timeseries
    assert eff.evaluations > 40 and eff.active_evaluations == 0
    assert all(np.array_equal(a[k], b[k]) for k in b)
    # without a band the same gap (below 1e-3) acts, and the run differs
    c = packed_tank(1.0, VolumeConsistency(band=0.0), steps=40)[1].timeseries
    assert not np.array_equal(c["kinetic_energy"], b["kinetic_energy"])


def test_compiled_kernel_agrees_with_the_numpy_reference():
    eff = VolumeConsistency()
    sim, _ = packed_tank(0.97, eff, steps=30)               # disordered by the re-expansion, a free surface
    s = sim.state.fluid
    k = get_kernel("cubic_spline")
    s.table = evaluate_shape_functions(s.x, s.x, s.h, s.neighbors, k, 1, kernel_sum_volumes=s.volume)
    least = eff.surface * eff.reference
    a = deep_particles(s.table, s.table.kernel_sum, s.n_fluid, least)
    b = deep_particles_reference(s.table, s.table.kernel_sum, s.n_fluid, least)
    assert np.array_equal(a, b)
    assert 0.3 * s.n_fluid < np.count_nonzero(a) < s.n_fluid
    near = wall_rows(s.table, s.n_fluid)
    assert np.array_equal(near, wall_rows_reference(s.table, s.n_fluid))
    assert 0 < np.count_nonzero(near) < 0.7 * s.n_fluid and not np.any(a & near)   # a deep particle is never a wall row


def test_idle_in_a_closed_tank():
    eff = VolumeConsistency(0.05)
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, 0.1), DX, [Phase("water", RHO)])
    fl.positions[:] *= 0.95
    walls = wall_box((0.0, 0.0), (0.2, 0.1), DX, layers=3, reference_density=RHO)
    sim = Simulation(Scene([fl, walls], [water(C0, spacing=DX, volume_consistency=0.0, extra=[ClosedVolume(), eff])], t_end=0.02))
    sim.run(progress=False)
    assert eff.idle and "ClosedVolume" in eff.summary()["idle"]


@pytest.mark.parametrize("kwargs, message", [
    ({"rate": 0.0}, "rate must be positive"),
    ({"rate": 0.2}, "at most 0.05"),
    ({"surface": 1.2}, "surface must be"),
    ({"band": -0.01}, "band must be"),
    ({"loose_band": 0.2}, "loose_band must be"),
    ({"loose_every": 0}, "loose_every must be"),
    ({"loose_local": -1.0}, "loose_local must be"),
    ({"loose_local_band": 1.5}, "loose_local_band must be"),
    ({"splash": 0.95}, "splash must be"),
])
def test_bad_settings_are_refused_before_step_1(kwargs, message):
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, 0.1), DX, [Phase("water", RHO)])
    scheme = water(C0, spacing=DX, volume_consistency=0.0, extra=[VolumeConsistency(**kwargs)])
    with pytest.raises(ValueError, match=message):
        Simulation(Scene([fl], [scheme], t_end=0.1))


def test_a_negative_rate_given_to_water_is_refused_not_dropped():
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, 0.1), DX, [Phase("water", RHO)])
    with pytest.raises(ValueError, match="rate must be positive"):
        Simulation(Scene([fl], [water(C0, spacing=DX, slip=None, volume_consistency=-0.01)], t_end=0.1))


@pytest.mark.parametrize("periodic", [True, False])
def test_acts_only_where_the_fluid_has_a_free_surface(periodic):
    # a block squeezed by 0.95 after its masses were set: its deep particles read a gap of 10.8 %.
    # In a periodic box of the squeezed side it fills its domain (no free surface: the effect
    # waits); the same block in open space has a free surface all round, and the effect acts
    from mlsgalerkin.periodic import Periodic
    side, dx = 0.95 * 0.4, 0.025
    fl = FluidBody.block("water", (0.0, 0.0), (0.4, 0.4), dx, [Phase("water", RHO)])
    fl.positions[:] *= 0.95
    eff = VolumeConsistency()
    scheme = water(10.0, gravity=None, slip=None, spacing=dx, negative_pressure="allow", volume_consistency=0.0,
                   extra=[eff], periodic=Periodic(x=(0.0, side), y=(0.0, side)) if periodic else None)
    Simulation(Scene([fl], [scheme], t_end=1.0)).run(max_steps=3, progress=False)
    report = eff.summary()
    assert eff.evaluations >= 3
    if periodic:
        assert eff.active_evaluations == 0 and "no free surface" in report["idle"]
    else:
        assert eff.active_evaluations == eff.evaluations and report["free_surface_share"] == 1.0
        assert report["packing_gap_mean_at_end"] == pytest.approx(1 / 0.95**2 - 1, rel=0.05)


def test_a_problem_lists_it_by_default_and_zero_leaves_it_out():
    from mlsgalerkin.fluid.scheme import FluidScheme
    from mlsgalerkin.problem import load_problem
    module = load_problem("dam_break")
    for rate, listed in ((None, True), (0.0, False)):
        params = module.Parameters(**getattr(module, "SMOKE", {}), **({} if rate is None else {"volume_consistency": rate}))
        scheme = next(sc for sc in module.make_scene(params).schemes if isinstance(sc, FluidScheme))
        assert any(isinstance(e, VolumeConsistency) for e in scheme.effects) is listed


def loose_top_tank(loose_band: float, t_end: float = 0.3, stretch: float = 1.38, rows: int = 3,
                   loose_local: float = 0.0):
    """The tank of :func:`packed_tank` at rest, but its top ``rows`` rows stand ``stretch`` spacings
    apart vertically (a settled splash's loose layer), at the hydrostatic densities of their new
    heights: the pressure holds the layer up at any packing. Returns the effect and the result."""
    fl = FluidBody.block("water", (0.0, 0.0), (0.4, DEPTH), DX, [Phase("water", RHO)])
    y = fl.positions[:, 1]
    y0 = DEPTH - rows * DX
    top = y > y0
    fl.positions[top, 1] = y0 + (y[top] - y0) * stretch
    surface = fl.positions[:, 1].max() + DX / 2
    fl.density[:] = hydrostatic_density(np.full(fl.n, RHO), surface - fl.positions[:, 1], G, C0)
    walls = wall_box((0.0, 0.0), (0.4, 0.4), DX, layers=3, reference_density=RHO)
    eff = VolumeConsistency(loose_band=loose_band, loose_local=loose_local)
    sim = Simulation(Scene([fl, walls], [water(C0, spacing=DX, volume_consistency=0.0, extra=[eff])], t_end=t_end))
    return eff, sim.run(progress=False)


def test_the_loose_side_closes_a_loose_surface_layer_and_without_it_the_layer_stays():
    # the three top rows 1.38 spacings apart (gaps of 0.38 spacings, which the geometric volume
    # closes at every pixel phase): a volume error of +10 % at the start. Their sums are cut by
    # the surface, so the deep mean does not see them; the loose side does
    on, res_on = loose_top_tank(0.01)
    off, res_off = loose_top_tank(0.0)
    err_on, err_off = (np.asarray(r.timeseries["volume_error"]) for r in (res_on, res_off))
    assert err_on[0] == err_off[0] == pytest.approx(0.10, abs=0.01)
    assert err_off[-1] > 0.05                  # measured 6.3 % at 0.3 s: the layer is held up
    assert err_on[-1] < 0.035                  # measured 1.8 % at 0.3 s, closing towards the band
    report = on.summary()
    assert report["loose_volume_error_largest"] == pytest.approx(err_on[0], abs=0.005)
    assert report["loose_active_share"] > 0.5 and "loose_band" not in off.summary()


def test_the_local_part_closes_the_loose_layer_faster():
    # the same layer with the local part: its particles away from the side walls stand about
    # 38 % looser than their volumes, far past the local band, so they relax faster than the
    # whole fluid's error alone drives them
    plain, res_plain = loose_top_tank(0.01)
    local, res_local = loose_top_tank(0.01, loose_local=2.0)
    err_plain, err_local = (np.asarray(r.timeseries["volume_error"]) for r in (res_plain, res_local))
    assert err_local[0] == err_plain[0]
    assert err_local[-1] < err_plain[-1] - 0.004        # measured 1.76 % without, 0.92 % with at 0.3 s
    report = local.summary()
    assert report["loose_local"] == 2.0 and report["loose_local_excess_largest"] > 0.2
    assert "loose_local" not in plain.summary()


def test_the_loose_side_within_its_band_changes_nothing():
    # a lattice's volume error is 0: the loose side measures it and never acts, so not a bit changes
    eff = VolumeConsistency(loose_band=0.01)
    a = packed_tank(1.0, eff, steps=40)[1].timeseries
    b = packed_tank(1.0, VolumeConsistency(), steps=40)[1].timeseries
    assert eff.loose_evaluations == 0 and abs(eff.loose_error_largest) < 0.01
    assert all(np.array_equal(a[k], b[k]) for k in b)


def test_loose_particles_are_neither_deep_nor_splashes():
    c = np.array([1.0, 0.95, 0.7, 0.4, 0.1])
    deep = np.array([True, False, False, False, False])
    assert loose_particles(c, deep, reference=1.0, splash=0.5).tolist() == [False, True, True, False, False]


def test_water_refuses_the_loose_side_without_the_volume_consistency():
    with pytest.raises(ValueError, match="loose side"):
        water(C0, spacing=DX, volume_consistency=0.0, loose_band=0.01)


def test_droplets_are_sparse_particles_above_their_rest_density():
    c = np.array([1.0, 0.6, 0.45, 0.3, 0.3])
    rho = np.array([1001.0, 1001.0, 1001.0, 1001.0, 999.0])
    assert droplets(c, rho, np.full(5, RHO), reference=1.0, splash=0.5).tolist() == [False, False, True, True, False]


def droplet_tank(droplet_rate: float, t_end: float = 0.1):
    """The tank of :func:`packed_tank` at rest (a lattice) with four droplets three spacings apart
    high above its surface, 1 % above the rest density (a droplet compressed when it met another).
    Returns the effect, the water block's size and the result."""
    block = FluidBody.block("water", (0.0, 0.0), (0.4, DEPTH), DX, [Phase("water", RHO)])
    drops = np.array([[0.1 + 3 * DX * k, 0.5] for k in range(4)])
    x = np.vstack([block.positions, drops])
    surface = DEPTH
    rho = hydrostatic_density(np.full(len(x), RHO), np.maximum(surface - x[:, 1], 0.0), G, C0)
    rho[block.n:] = 1.01 * RHO
    fl = FluidBody("water", x, DX, [Phase("water", RHO)], density=rho)
    walls = wall_box((0.0, 0.0), (0.4, 0.6), DX, layers=3, reference_density=RHO)
    eff = VolumeConsistency(loose_band=0.0, droplet_rate=droplet_rate)
    sim = Simulation(Scene([fl, walls], [water(C0, spacing=DX, volume_consistency=0.0, extra=[eff])], t_end=t_end))
    return eff, block.n, sim.run(progress=False)


def test_a_droplet_loses_the_pressure_it_was_compressed_to():
    # a droplet alone has no neighbours to exchange density with, so its continuity keeps the 1 %
    # excess (the 0.25 kPa of a droplet that held a cloud of them up in beam_clamped); relaxed at
    # 0.1 c0/h (tau = 13 ms here) it is back at the rest density within the 0.1 s (measured 1000.005)
    on, n_block, res_on = droplet_tank(0.1)
    off, _, res_off = droplet_tank(0.0)
    rho_on, rho_off = (r.state.fluid.rho[: r.state.fluid.n_fluid] for r in (res_on, res_off))
    n_fluid = res_on.state.fluid.n_fluid
    assert res_on.state.fluid.x[n_block:n_fluid, 1].min() > DEPTH + 3 * DX      # still droplets: far above the water
    assert np.all(rho_off[n_block:] > 1.009 * RHO)
    assert np.all(rho_on[n_block:] < 1.0001 * RHO)
    assert on.summary()["droplets_largest"] == 4 and "droplet_rate" not in off.summary()


def test_the_top_row_of_still_water_is_no_droplet():
    # its Shepard sum is above half the lattice's: still water runs as without the droplet side, bit for bit
    eff = VolumeConsistency(droplet_rate=0.1)
    a = packed_tank(1.0, eff, steps=40)[1].timeseries
    b = packed_tank(1.0, VolumeConsistency(droplet_rate=0.0), steps=40)[1].timeseries
    assert eff.droplet_evaluations == 0 and eff.droplets_largest == 0
    assert all(np.array_equal(a[k], b[k]) for k in b)
