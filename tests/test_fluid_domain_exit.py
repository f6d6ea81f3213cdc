"""Fluid particles that leave the domain are taken out of the run
(:mod:`mlsgalerkin.fluid.domain_exit`): the domain's bounds, the particles held where they left,
out of every neighbour table, the time step and the run checks, counted and warned."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from mlsgalerkin.fluid import (
    FluidBody,
    Gravity,
    MonaghanViscosity,
    Phase,
    TaitPressure,
    Walls,
    wall_box,
)
from mlsgalerkin.fluid.domain_exit import (
    EXIT_TIME,
    MARGIN_RADII,
    OUTSIDE,
    DomainExit,
    ParticlesLeftDomainWarning,
    mark_and_hold,
    mark_and_hold_reference,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.scene import Output, Scene
from mlsgalerkin.simulation import Simulation

DX = 0.02
WATER = [Phase("water", 1000.0)]


def test_the_domain_is_the_starting_box_widened_and_open_above():
    x = np.array([[0.0, 0.0], [1.0, 0.5]])
    d = DomainExit.around(x, 0.1, np.array([0.0, -9.81]))
    np.testing.assert_allclose(d.lower, [-MARGIN_RADII * 0.1, -MARGIN_RADII * 0.1])
    assert d.upper[0] == pytest.approx(1.0 + MARGIN_RADII * 0.1) and d.upper[1] == math.inf
    no_gravity = DomainExit.around(x, 0.1, None)
    assert np.all(np.isfinite(no_gravity.upper))
    periodic = DomainExit.around(x, 0.1, np.array([0.0, -9.81]), periodic_axes=(0,))
    assert periodic.lower[0] == -math.inf and periodic.upper[0] == math.inf and np.isfinite(periodic.lower[1])
    assert DomainExit.around(x, 0.1, None, periodic_axes=(0, 1)) is None   # nothing to leave


def test_the_domain_follows_walls_that_move_out_of_the_starting_box():
    # a beam leaning out of the tank carries water beyond the starting box: the bound follows the
    # wall particles where they are now, and returns to the starting box when they come back
    x = np.array([[0.0, 0.0], [1.0, 0.5]])
    d = DomainExit.around(x, 0.1, np.array([0.0, -9.81]))
    start_upper = d.upper.copy()
    d.follow_walls(np.array([[1.5, 0.2], [0.5, 0.0]]))
    assert d.upper[0] == pytest.approx(1.5 + MARGIN_RADII * 0.1) and d.upper[1] == math.inf
    np.testing.assert_array_equal(d.lower, d.start_lower)        # walls inside the box change nothing
    d.follow_walls(np.array([[0.9, 0.2]]))
    np.testing.assert_array_equal(d.upper, start_upper)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_the_marking_kernel_agrees_with_its_numpy_reference(dim, rng):
    n, n_fluid = 400, 300
    x = rng.uniform(-1.2, 1.2, (n, dim))
    lower, upper = np.full(dim, -1.0), np.full(dim, 1.0)
    upper[-1] = np.inf
    out0 = rng.random(n) < 0.1
    out0[n_fluid:] = False
    arrays = [out0, rng.normal(size=(n, dim)), rng.normal(size=(n, dim)), rng.normal(size=n)]
    a_copy = [a.copy() for a in arrays]
    b_copy = [a.copy() for a in arrays]
    new_a = mark_and_hold(x, n_fluid, lower, upper, *a_copy)
    new_b = mark_and_hold_reference(x, n_fluid, lower, upper, *b_copy)
    assert new_a.size > 10
    np.testing.assert_array_equal(new_a, new_b)
    for u, w in zip(a_copy, b_copy):
        np.testing.assert_array_equal(u, w)
    assert not a_copy[0][n_fluid:].any()                                # never a wall row


def _scene(domain_exit: bool = True, t_end: float = 0.06) -> Scene:
    """A small open tank with water at rest, and two particles one spacing apart thrown
    sideways over its right wall at 8 m/s (they leave the domain after about 23 and 25 ms)."""
    water = FluidBody.block("water", (0.0, 0.0), (0.3, 0.1), DX, WATER)
    spray = FluidBody("spray", np.array([[0.28, 0.36], [0.3, 0.36]]), DX, WATER, velocity=(8.0, 0.0))
    walls = wall_box((0.0, 0.0), (0.32, 0.3), DX)
    effects = [TaitPressure(20.0), Gravity(), Walls(), MonaghanViscosity(0.1)]
    scheme = FluidScheme(effects, stabilisation="as_listed", domain_exit=domain_exit)
    return Scene([water, spray, walls], [scheme], t_end=t_end)


def _run(scene: Scene):
    sim = Simulation(scene)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sim.run(progress=False)
    return sim, res, [w for w in caught if issubclass(w.category, ParticlesLeftDomainWarning)]


def test_particles_thrown_out_of_the_tank_are_taken_out_of_the_run():
    sim, res, caught = _run(_scene())
    s = sim.state.fluid
    spray = np.arange(s.bodies["spray"].start, s.bodies["spray"].stop)
    out = s.extra[OUTSIDE]
    assert np.all(out[spray]) and out.sum() == 2               # the spray alone, never a wall row
    assert np.all(s.v[spray] == 0.0) and np.all(s.a[spray] == 0.0) and np.all(s.drho[spray] == 0.0)
    assert np.all(s.x[spray, 0] > sim.solvers[0].domain_exit.upper[0])   # held just past the bound
    # in nobody's neighbour row, and each one's own row is itself alone
    nb = s.neighbors
    rows = np.repeat(np.arange(s.n), np.diff(nb.indptr))
    for k in spray:
        assert np.all((nb.indices == k) == (rows == k))
    # the trailing particle flew through where the leading one is held, untouched: it left one
    # spacing's flight (2.5 ms at 8 m/s) later, within a step (about 0.4 ms); pushed by the held one
    # (were it in the neighbour search) it left 3.2 ms later
    times = s.extra[EXIT_TIME][spray]
    assert times[0] - times[1] == pytest.approx(DX / 8.0, abs=2e-4)
    ts = res.timeseries
    assert ts["particles_outside"][0] == 0 and ts["particles_outside"][-1] == 2
    assert ts["max_speed"][-1] < 1.0                          # the water in the tank, not the spray
    rep = res.summary["fluid"]["domain_exit"]
    assert rep["particles_outside"] == 2 and rep["mass_outside_kg"] == pytest.approx(s.M[spray].sum())
    assert rep["first_exit_s"] == pytest.approx(times.min()) and rep["last_exit_s"] == pytest.approx(times.max())
    assert rep["upper_m"][1] is None                          # open above
    assert res.summary["fluid"]["diagnostics"]["total_mass_kg"] == pytest.approx(s.M[: s.n_fluid].sum())  # kept
    assert len(caught) == 1 and "left the domain" in str(caught[0].message)
    assert f"{sim.solvers[0].domain_exit.upper[0]:.4g}" in str(caught[0].message)   # the bound it crossed
    # out of every structure's reach: the contact sees them parked beyond the domain, the rest where they are
    surface = sim.solvers[0].surface("spray")
    assert np.all(surface.positions[:, 0] < sim.solvers[0].domain_exit.lower[0])
    water = sim.solvers[0].surface("water")
    np.testing.assert_array_equal(water.positions, s.x[s.bodies["water"]])


def test_without_it_the_particle_keeps_falling_and_sets_the_step():
    _, res_on, _ = _run(_scene())
    sim_off, res_off, caught = _run(_scene(domain_exit=False))
    assert not caught and res_off.summary["fluid"]["domain_exit"] is None
    assert "particles_outside" not in res_off.timeseries
    s = sim_off.state.fluid
    k = s.bodies["spray"].start
    assert np.linalg.norm(s.v[k]) > 8.0                       # still flying, faster
    assert res_off.timeseries["max_speed"][-1] > 8.0
    # the water alone sets the step once the spray is out: fewer steps to the same end
    assert res_on.summary["steps"] < res_off.summary["steps"]


def test_the_water_left_in_the_tank_is_the_same_with_or_without_it_until_the_exit():
    sim_on = _run(_scene(t_end=0.01))[0]
    sim_off = _run(_scene(domain_exit=False, t_end=0.01))[0]
    np.testing.assert_array_equal(sim_on.state.fluid.x, sim_off.state.fluid.x)   # bit for bit before it


def test_a_restart_after_the_exit_continues_bit_for_bit(tmp_path):
    """Checkpoints every 10 ms; the run stopped at 24 ms (between the two exits, 23 and 25 ms) and
    restarted ends where the uninterrupted run does, the particles out the same."""
    def scene():
        sc = _scene(t_end=0.05)
        sc.output = Output(checkpoint_every=0.01)
        return sc

    ref = Simulation(scene()).run(out=tmp_path / "ref", progress=False)
    t_stop = 0.024
    steps = int(np.searchsorted(ref.timeseries["time"], t_stop))
    part = Simulation(scene()).run(out=tmp_path / "part", progress=False, max_steps=int(ref.timeseries["step"][steps]))
    assert part.state.fluid.extra[OUTSIDE].sum() == 1
    res = Simulation(scene()).run(out=tmp_path / "part", restart="latest", progress=False)
    a, b = ref.state.fluid, res.state.fluid
    for k in ("x", "v", "rho", "a"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    assert np.array_equal(a.extra[OUTSIDE], b.extra[OUTSIDE]) and b.extra[OUTSIDE].sum() == 2
    assert np.array_equal(a.extra[EXIT_TIME], b.extra[EXIT_TIME], equal_nan=True)
    assert ref.summary["fluid"]["domain_exit"] == res.summary["fluid"]["domain_exit"]
