"""The fluid solver (:mod:`mlsgalerkin.simulation`) on small scenes: conservation, rest,
free fall, the watchdog, checkpoint/restart, output files and hard cases (splash, tension,
collinear particles, a drop impact, a long hydrostatic run).

Numbers quoted in comments were measured with the default settings (cubic spline,
``h = 1.3 Δx``, linear MLS, skin 0.15 Δx).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.fluid import (
    BulkViscosity,
    DensityFilter,
    Effect,
    FluidBody,
    FreeSurfaceDetection,
    Gravity,
    MonaghanViscosity,
    NewtonianViscosity,
    Phase,
    TaitEOS,
    TaitPressure,
    Walls,
    lattice,
    wall_box,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.io import latest_checkpoint, load_checkpoint, read_pvd, read_timeseries
from mlsgalerkin.scene import Approximation, Output, Probe, Scene, Watchdog
from mlsgalerkin.simulation import RestartMismatch, Simulation, SimulationDiverged

G = 9.81
GVEC = np.array([0.0, -G])
WATER = [Phase("water", 1000.0)]


# ------------------------------------------------------------------------------ scenes

def _scheme_options(kw: dict) -> dict:
    """Take the fluid scheme's options (approximation, integrator, mass, safety, dt_max) out of ``kw``."""
    return {k: kw.pop(k) for k in ("approximation", "integrator", "mass", "safety", "dt_max") if k in kw}

def hydrostatic_tank(dx=0.02, H=0.4, W=0.4, t_end=0.3, effects=None, **scene_kw) -> Scene:
    """Water at hydrostatic rest in a walled box (free-slip walls, open top)."""
    c0 = 10.0 * math.sqrt(2.0 * G * H)
    eos = TaitEOS(1000.0, c0)
    fl = FluidBody.block("water", (0.0, 0.0), (W, H), dx, WATER)
    fl.density[:] = eos.density(1000.0 * G * (H - fl.positions[:, 1]))
    walls = wall_box((0.0, 0.0), (W, 1.5 * H), dx, layers=3)
    if effects is None:
        effects = [MonaghanViscosity(0.1), DensityFilter(20)]
    listed = [TaitPressure(c0), Gravity(), Walls("free_slip")] + list(effects)
    return Scene([fl, walls], [FluidScheme(listed, **_scheme_options(scene_kw), stabilisation="as_listed")], t_end=t_end, name="hydrostatic_tank", **scene_kw)


def free_block(dx=0.02, size=0.2, velocity=(0.0, 0.0), effects=(), gravity=False, c0=20.0,
               t_end=0.05, **scene_kw) -> Scene:
    """A block of water at the reference density (p = 0), no walls."""
    fl = FluidBody.block("water", (0.0, 0.0), (size, size), dx, WATER, velocity=velocity)
    listed = [TaitPressure(c0)] + ([Gravity()] if gravity else []) + list(effects)
    return Scene([fl], [FluidScheme(listed, **_scheme_options(scene_kw), stabilisation="as_listed")], t_end=t_end, **scene_kw)


# ------------------------------------------------------------------ hydrostatic (shared)
@pytest.fixture(scope="module")
def tank_run(tmp_path_factory):
    """The hydrostatic tank of the docs (dx = 0.02 m, H = 0.4 m, Monaghan α = 0.1, density
    filter every 20 steps) run for 0.3 s with output; ~870 steps."""
    out = tmp_path_factory.mktemp("tank")
    scene = hydrostatic_tank(output=Output(every=0.1))
    sim = Simulation(scene)
    M0 = sim.state.fluid.M[sim.state.fluid.fluid].copy()
    res = sim.run(out=out, progress=False)
    return res, M0, scene


def test_total_mass_is_exact(tank_run):
    res, M0, _ = tank_run
    s = res.state.fluid
    assert np.array_equal(s.M[s.fluid], M0)  # particle masses never change
    m = res.timeseries["total_mass"]
    assert len(m) > 800 and np.all(m == m[0])  # Σ M identical to the bit at every step


def test_hydrostatic_tank_stays_at_rest(tank_run):
    res, _, _ = tank_run
    s, ts = res.state.fluid, res.timeseries
    f = s.fluid
    H, W, dx = 0.4, 0.4, 0.02
    # Measured: largest speed 0.89 % of sqrt(gH) (0.0177 m/s, the free-surface corner particle
    # during the acoustic transient at t ≈ 0.09 s), 0.33 % at t = 0.3 s. Bound 1.2 %: 35 % above
    # the measured peak, below the 1.87 % the same tank reaches when the hydrostatic term of the
    # wall-pressure extrapolation is removed (Walls._g = 0), so it detects that error.
    assert ts["max_speed"].max() < 0.012 * math.sqrt(G * H)
    assert ts["max_speed"][-1] < ts["max_speed"].max()  # the transient decays
    # nothing crosses the walls (free-slip walls at x = 0, x = W, y = 0)
    assert np.all((s.x[f, 0] > 0.0) & (s.x[f, 0] < W) & (s.x[f, 1] > 0.0))
    assert s.x[f, 0].min() > 0.25 * dx and s.x[f, 1].min() > 0.25 * dx
    # pressure vs ρ0 g (H − y): measured RMS error 0.23 % of ρ0 g H at t = 0.3 s (0.99 % without
    # the wall hydrostatic term); bound 0.5 %, well inside the 2 % asked of the tank
    p_h = 1000.0 * G * (H - s.x[f, 1])
    rms = math.sqrt(float(np.mean((s.p[f] - p_h) ** 2)))
    assert rms < 0.005 * 1000.0 * G * H
    # kinetic energy decays after the initial transient (Monaghan viscosity damps it)
    ke = ts["kinetic_energy"]
    assert ke[-1] < ke.max()


def test_output_files(tank_run):
    res, _, scene = tank_run
    out = res.out
    ts = read_timeseries(out / "timeseries.csv")
    for col in ("time", "dt", "step", "kinetic_energy", "total_mass", "potential_energy", "momentum_x",
                "momentum_y", "max_speed", "min_density_ratio", "max_density_ratio", "fallback_points"):
        assert col in ts
    assert ts["time"][0] == 0.0 and ts["time"][-1] == pytest.approx(scene.t_end, abs=1e-12)
    assert np.all(np.diff(ts["step"]) == 1) and np.all(np.diff(ts["time"]) > 0)
    assert np.allclose(np.diff(ts["time"]), ts["dt"][1:], rtol=1e-9, atol=0)
    frames = read_pvd(out / "particles.pvd")
    assert [t for t, _ in frames] == pytest.approx([0.0, 0.1, 0.2, 0.3], abs=1e-3)
    assert all(p.is_file() for _, p in frames)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["wall_time_s"] > 0
    assert "tait_pressure" in summary["fluid"]["time_per_stage_s"] and "walls" in summary["fluid"]["time_per_stage_s"]
    d = summary["fluid"]["diagnostics"]
    for key in ("shape_function_fallback_points", "lumped_mass_floored", "neighbour_rebuilds",
                "total_mass_kg", "kinetic_energy_J", "momentum"):
        assert key in d
    assert d["total_mass_kg"] == pytest.approx(1000.0 * 0.4 * 0.4, rel=0.02)
    assert latest_checkpoint(out / "checkpoints") is not None


# ------------------------------------------------------------------------- conservation
def test_momentum_conserved_with_particle_mass(rng):
    """No walls, no gravity, ``mass="particle"``: Σ M v is conserved to round-off (the
    Galerkin internal force sums to zero, Σ_i ∇N_i = 0, and the Monaghan pair force is
    antisymmetric). Measured drift 2e-16 of Σ M |v| over 200 steps."""
    fl = FluidBody.block("water", (0.0, 0.0), (0.3, 0.3), 0.02, WATER)
    fl.velocity[:] = rng.normal(0.0, 0.1, fl.velocity.shape)
    scene = Scene([fl], [FluidScheme([TaitPressure(10.0), MonaghanViscosity(0.1)], mass="particle", stabilisation="as_listed")], t_end=1.0)
    sim = Simulation(scene)
    res = sim.run(progress=False, max_steps=200)
    s = res.state.fluid
    assert s.step == 200
    M = s.M[s.fluid]
    P0 = M @ fl.velocity
    scale = float(M @ np.linalg.norm(fl.velocity, axis=1))
    assert np.abs(s.momentum() - P0).max() <= 1e-12 * scale
    assert s.kinetic_energy() < 0.5 * float(M @ np.einsum("ij,ij->i", fl.velocity, fl.velocity))


def test_lumped_mass_force_sums_to_zero(rng):
    """Default lumped mass: every evaluation's total force Σ_i f_i vanishes to round-off
    (measured 5e-17 of Σ|f|). Σ M v itself is *not* conserved with the lumped mass
    (a = f/m_i with m_i ≠ M_i; measured drift 1.1 % of Σ M|v| over 200 steps), so only the
    force sum is asserted."""
    fl = FluidBody.block("water", (0.0, 0.0), (0.3, 0.3), 0.02, WATER)
    fl.velocity[:] = rng.normal(0.0, 0.1, fl.velocity.shape)
    sim = Simulation(Scene([fl], [FluidScheme([TaitPressure(10.0), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=1.0))
    sim.start()
    s = sim.state.fluid
    worst = 0.0
    for _ in range(200):
        sim.step(s.dt_next)
        f = s.force[s.fluid]
        worst = max(worst, float(np.abs(f.sum(axis=0)).max() / np.abs(f).sum()))
    assert worst < 1e-13


def test_uniform_translation_stays_uniform():
    U = np.array([0.5, 0.2])
    scene = free_block(size=0.3, velocity=U, effects=[MonaghanViscosity(0.1)], c0=10.0, t_end=0.2)
    sim = Simulation(scene)
    x0 = sim.state.fluid.x.copy()
    s = sim.run(progress=False).state.fluid
    assert s.step > 150
    # measured: velocity and density unchanged to the bit, positions to 5e-15 m
    np.testing.assert_allclose(s.v, np.broadcast_to(U, s.v.shape), rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.rho, 1000.0, rtol=1e-14, atol=0)
    np.testing.assert_allclose(s.x, x0 + U * s.t, rtol=0, atol=1e-12)


# --------------------------------------------------------------------------- free fall
@pytest.mark.parametrize("integrator", ["kdk", "predictor_corrector"])
@pytest.mark.parametrize("mass", ["lumped", "particle"])
def test_free_fall_is_exact(integrator, mass):
    """A block at ρ0 (p = 0) falling under gravity: x = x0 + v0 t + ½ g t² for both
    integrators (both are exact for a constant acceleration; measured error 1e-16 m)."""
    v0 = np.array([0.3, 0.1])
    scene = free_block(velocity=v0, gravity=True, integrator=integrator, mass=mass)
    sim = Simulation(scene)
    x0 = sim.state.fluid.x.copy()
    s = sim.run(progress=False).state.fluid
    assert s.t == pytest.approx(0.05, abs=1e-15)
    np.testing.assert_allclose(s.x, x0 + v0 * s.t + 0.5 * GVEC * s.t**2, rtol=0, atol=1e-13)
    np.testing.assert_allclose(s.v, np.broadcast_to(v0 + GVEC * s.t, s.v.shape), rtol=0, atol=1e-13)
    np.testing.assert_allclose(s.a, np.broadcast_to(GVEC, s.a.shape), rtol=0, atol=1e-12)


def test_predictor_corrector_agrees_with_kdk():
    v0 = (0.3, 0.1)
    runs = [Simulation(free_block(velocity=v0, gravity=True, integrator=i)).run(progress=False).state.fluid
            for i in ("kdk", "predictor_corrector")]
    assert runs[0].step == runs[1].step
    np.testing.assert_allclose(runs[0].x, runs[1].x, rtol=0, atol=1e-14)
    np.testing.assert_allclose(runs[0].v, runs[1].v, rtol=0, atol=1e-13)


def test_consistent_mass_gives_gravity_acceleration():
    """``mass="consistent"``: m_ij a_j = m_i g has the exact solution a = g (the rows of the
    consistent mass sum to the lumped mass). The CG solve (relative residual 1e-10) on a
    matrix of condition number ~2e5 gives it to 1e-10 relative at t = 0 (measured: 4e-10
    without, 9e-11 with the Jacobi preconditioner) and 3e-9 after one step."""
    v0 = np.array([0.3, 0.1])
    sim = Simulation(free_block(velocity=v0, gravity=True, mass="consistent"))
    x0 = sim.state.fluid.x.copy()
    sim.start()
    s = sim.state.fluid
    np.testing.assert_allclose(s.a, np.broadcast_to(GVEC, s.a.shape), rtol=0, atol=1e-7 * G)
    sim.step(s.dt_next)
    np.testing.assert_allclose(s.a, np.broadcast_to(GVEC, s.a.shape), rtol=0, atol=1e-6 * G)
    np.testing.assert_allclose(s.x, x0 + v0 * s.t + 0.5 * GVEC * s.t**2, rtol=0, atol=1e-12)


@pytest.mark.filterwarnings("ignore:consistent-mass CG did not converge:RuntimeWarning")
def test_consistent_mass_is_ill_conditioned_and_the_watchdog_stops_it():
    """Documented limitation (docs/theory/galerkin_fluid.md): the MLS consistent mass
    m_ij = Σ_k M_k N_i(x_k) N_j(x_k) has eigenvalues down to ~5e-6 of the particle mass, so its
    modes are far above the acoustic CFL limit and a free fall diverges within ~20 steps (also
    with an exact solve). What must hold: the cause is measurable, and the run is stopped by
    the watchdog with a diagnosis instead of returning NaN."""
    from mlsgalerkin.assembly import consistent_mass

    sim = Simulation(free_block(velocity=(0.3, 0.1), gravity=True, mass="consistent"))
    sim.start()
    Mc = consistent_mass(sim.state.fluid.table, sim.state.fluid.M).toarray()
    eig = np.linalg.eigvalsh(Mc)
    assert eig.min() < 1e-3 * sim.state.fluid.M.mean()  # measured ~5e-6: near-singular
    with pytest.raises(SimulationDiverged) as info:
        sim.run(progress=False)
    assert info.value.diagnosis["step"] < 100 and info.value.diagnosis["quantity"]


# ----------------------------------------------------------------------------- watchdog
class PoisonForce(Effect):
    """Writes NaN into one particle's force during the step that ends as ``step``."""

    name = "poison_force"
    stages = ("force",)

    def __init__(self, step: int, particle: int) -> None:
        self.step, self.particle = step, particle

    def force(self, s):
        if s.step == self.step - 1:
            s.force[self.particle] = np.nan


def test_watchdog_names_step_particle_and_quantity(tmp_path):
    scene = free_block(gravity=True, effects=[PoisonForce(step=5, particle=7)], t_end=1.0,
                       watchdog=Watchdog(keep_every=2))
    with pytest.raises(SimulationDiverged) as info:
        Simulation(scene).run(out=tmp_path, progress=False)
    err = info.value
    msg = str(err)
    assert "step 5" in msg and "particle 7" in msg and "velocity" in msg and "not finite" in msg
    d = err.diagnosis
    assert d["step"] == 5 and d["particle"] == 7 and d["quantity"] == "velocity"
    assert d["body"] == "water" and d["neighbours"] > 0 and len(d["position"]) == 2
    assert not np.all(np.isfinite(d["value"]))
    # the last good state (kept every 2 steps: step 4) is on disk and loads
    assert err.checkpoint == tmp_path / "checkpoints" / "last_good.npz"
    assert err.checkpoint.is_file() and str(err.checkpoint) in msg
    arrays, meta = load_checkpoint(err.checkpoint)
    assert meta["step"] == 4
    assert all(np.all(np.isfinite(arrays[f"fluid__{k}"])) for k in ("x", "v", "rho", "a"))
    # the time series is flushed up to the last healthy step
    ts = read_timeseries(tmp_path / "timeseries.csv")
    assert ts["step"][-1] == 4
    # the loop's end wrote the summary of the stopped run, with the diagnosis
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "diverged" and summary["diagnosis"]["particle"] == 7
    assert summary["steps"] == 5 and summary["fluid"]["particles"]["fluid"] == s_n_fluid(scene)
    # the last good state restarts in a scene without the poison: a change of the physics, so it
    # is refused unless allowed, and then recorded in the summary
    clean = free_block(gravity=True, t_end=0.01)
    with pytest.raises(RestartMismatch, match="PoisonForce"):
        Simulation(clean).run(out=tmp_path, restart=err.checkpoint, progress=False)
    res = Simulation(clean).run(out=tmp_path, restart=err.checkpoint, progress=False, allow_changes=True)
    s = res.state.fluid
    assert s.t == pytest.approx(0.01) and np.all(np.isfinite(s.v))
    changed = res.summary["continued_with_changes"][0]
    assert changed["step"] == 4 and "PoisonForce" in changed["changes"][0]


def s_n_fluid(scene: Scene) -> int:
    return sum(b.n for b in scene.bodies_of(FluidBody))


def test_watchdog_speed_limit():
    scene = free_block(gravity=True, t_end=1.0, watchdog=Watchdog(max_speed=0.5))
    with pytest.raises(SimulationDiverged) as info:
        Simulation(scene).run(progress=False)
    d = info.value.diagnosis
    assert d["quantity"] == "velocity" and "exceeds 0.5 m/s" in d["problem"]
    assert d["time"] == pytest.approx(0.5 / G, abs=0.003)  # free fall reaches 0.5 m/s
    assert info.value.checkpoint is None and "kept in memory" in str(info.value)


# ---------------------------------------------------------------- checkpoint / restart
def _restart_scene(method: str = "mls", integrator: str = "kdk") -> Scene:
    dx, H = 0.04, 0.2
    c0 = 10.0 * math.sqrt(2.0 * G * H)
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, H), dx, WATER, velocity=(0.3, 0.0))
    walls = wall_box((0.0, 0.0), (0.4, 0.4), dx, layers=3)
    effects = [TaitPressure(c0), Gravity(), Walls("free_slip"), MonaghanViscosity(0.1), DensityFilter(5),
               FreeSurfaceDetection()]
    return Scene([fl, walls], [FluidScheme(effects, approximation=Approximation(method=method), integrator=integrator, stabilisation="as_listed")], t_end=0.1, output=Output(checkpoint_every=0.02))


def _assert_same_run(a, b, dir_a: Path, dir_b: Path) -> None:
    for k in ("x", "v", "rho", "p", "M", "a"):
        assert np.array_equal(getattr(a.state.fluid, k), getattr(b.state.fluid, k)), k
    assert np.array_equal(a.state.fluid.extra["free_surface"], b.state.fluid.extra["free_surface"])
    assert a.state.step == b.state.step and a.state.t == b.state.t
    ta, tb = read_timeseries(dir_a / "timeseries.csv"), read_timeseries(dir_b / "timeseries.csv")
    assert list(ta) == list(tb)
    for k in ta:
        assert np.array_equal(ta[k], tb[k]), k
    assert a.summary["fluid"]["diagnostics"] == b.summary["fluid"]["diagnostics"]
    assert a.summary["fluid"]["effect_reports"] == b.summary["fluid"]["effect_reports"]
    checks_a, checks_b = dict(a.summary["fluid"]["run_checks"]), dict(b.summary["fluid"]["run_checks"])
    assert checks_a.pop("time_s") >= 0 and checks_b.pop("time_s") >= 0   # wall time: differs
    assert checks_a == checks_b


RESTART_CASES = [("mls", "kdk"), ("rkpm", "kdk"), ("mls", "predictor_corrector")]


@pytest.fixture(scope="module", params=RESTART_CASES, ids=["-".join(c) for c in RESTART_CASES])
def uninterrupted(request, tmp_path_factory):
    """The reference run of the restart tests: (method, integrator), its result and folder.
    RKPM's table depends on the volumes M/ρ at the last kinematics, which the checkpoint
    stores (``table_volumes``) — ρ has had a half-step update since."""
    out = tmp_path_factory.mktemp("uninterrupted")
    res = Simulation(_restart_scene(*request.param)).run(out=out, progress=False)
    assert res.summary["steps"] > 90 and res.summary["fluid"]["diagnostics"]["neighbour_rebuilds"] > 10
    return request.param, res, out


def test_restart_after_interruption_is_bit_for_bit(uninterrupted, tmp_path):
    case, ref, ref_dir = uninterrupted
    part = Simulation(_restart_scene(*case)).run(out=tmp_path, progress=False, max_steps=37)
    assert part.state.step == 37
    res = Simulation(_restart_scene(*case)).run(out=tmp_path, restart="latest", progress=False)
    _assert_same_run(ref, res, ref_dir, tmp_path)


def test_restart_after_crash_from_periodic_checkpoint_is_bit_for_bit(uninterrupted, tmp_path):
    case, ref, ref_dir = uninterrupted
    Simulation(_restart_scene(*case)).run(out=tmp_path, progress=False, max_steps=50)
    # a crash loses the checkpoint written at the end: continue from the last periodic one,
    # the time series rows written after it are dropped and recomputed
    latest = latest_checkpoint(tmp_path / "checkpoints")
    assert load_checkpoint(latest)[1]["step"] == 50
    latest.unlink()
    assert load_checkpoint(latest_checkpoint(tmp_path / "checkpoints"))[1]["step"] < 50
    res = Simulation(_restart_scene(*case)).run(out=tmp_path, restart="latest", progress=False)
    _assert_same_run(ref, res, ref_dir, tmp_path)


# --------------------------------------------------------------------------- hard cases
def test_splash_isolated_particles_fly_ballistically():
    """A block plus isolated particles far away (a single one, a pair and a triangle) thrown
    with v0 under gravity: the single particle and the pair fall back to Shepard (order 0),
    nothing becomes NaN, and every isolated particle follows x0 + v0 t + ½ g t² exactly
    (partition of unity: their lumped mass is M, their stress force vanishes)."""
    dx = 0.02
    block = lattice((0.0, 0.0), (0.2, 0.2), dx)
    iso = np.array([[1.0, 1.0],                                          # alone
                    [2.0, 0.5], [2.0 + 0.6 * dx, 0.5],                   # a pair
                    [3.0, 1.0], [3.0 + dx, 1.0], [3.0 + 0.5 * dx, 1.0 + 0.8 * dx]])  # a triangle
    nb = len(block)
    v0 = np.array([1.5, 2.0])
    v = np.zeros((nb + len(iso), 2))
    v[nb:] = v0
    fl = FluidBody("water", np.vstack([block, iso]), dx, WATER, velocity=v)
    scene = Scene([fl], [FluidScheme([TaitPressure(20.0), Gravity(), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=0.1)
    res = Simulation(scene).run(progress=False)
    s = res.state.fluid
    assert np.all(np.isfinite(s.x)) and np.all(np.isfinite(s.v)) and np.all(np.isfinite(s.rho))
    assert s.table.order[nb:nb + 3].tolist() == [0, 0, 0]  # single and pair: Shepard
    assert s.table.order[nb + 3:].tolist() == [1, 1, 1]    # a triangle supports linear MLS
    assert res.summary["fluid"]["diagnostics"]["shape_function_fallback_points"] >= 3 * (s.step + 1)
    t = s.t
    np.testing.assert_allclose(s.x[nb:], iso + v0 * t + 0.5 * GVEC * t**2, rtol=0, atol=1e-13)
    v_exact = np.broadcast_to(v0 + GVEC * t, (len(iso), 2))
    np.testing.assert_allclose(s.v[nb:], v_exact, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(s.rho[nb:], 1000.0)


def test_expansion_reports_tensile_instability():
    fl = FluidBody.block("water", (0.0, 0.0), (0.2, 0.2), 0.02, WATER)
    fl.velocity[:] = 0.5 * (fl.positions - 0.1)  # uniform expansion, ∇·v = 1 /s
    scene = Scene([fl], [FluidScheme([TaitPressure(20.0), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=0.02)
    res = Simulation(scene).run(progress=False)
    ti = res.summary["fluid"]["effect_reports"]["tait_pressure"]["tensile_instability"]
    # measured: min pressure −1.5 kPa, all particles in tension
    assert ti["min_pressure_Pa"] < -500.0
    assert ti["max_fraction_negative"] > 0.5
    assert ti["steps_with_negative_pressure"] > 0 and ti["mode"] == "allow"
    assert res.state.fluid.p.min() < 0


def test_collinear_row_runs_without_nan(rng):
    """A single row of particles (moment matrix singular in 2D): every point falls back to
    order 0 and the run stays finite."""
    dx, n = 0.02, 20
    x = np.stack([np.arange(n) * dx, 1e-9 * dx * rng.standard_normal(n)], axis=1)
    v = np.stack([0.1 * np.sin(np.arange(n)), np.zeros(n)], axis=1)
    fl = FluidBody("row", x, dx, WATER, velocity=v)
    scene = Scene([fl], [FluidScheme([TaitPressure(20.0), Gravity(), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=0.05)
    res = Simulation(scene).run(progress=False)
    s = res.state.fluid
    assert s.step > 50
    for arr in (s.x, s.v, s.rho, s.p, s.a):
        assert np.all(np.isfinite(arr))
    assert np.all(s.table.order == 0)
    assert res.summary["fluid"]["diagnostics"]["shape_function_fallback_points"] == n * (s.step + 1)
    assert 0.98 < s.rho.min() / 1000.0 and s.rho.max() / 1000.0 < 1.02  # measured 0.997–1.0045


def _tait_internal_energy(c0: float, gamma: float = 7.0):
    """Σ M e(ρ) with e = ∫ p/ρ² dρ = (B/ρ0) [r^(γ−1)/(γ−1) + 1/r − γ/(γ−1)], r = ρ/ρ0."""
    def energy(state) -> float:
        s = state.fluid
        f = s.fluid
        r = s.rho[f] / s.rho0[f]
        B = s.rho0[f] * c0**2 / gamma
        e = B / s.rho0[f] * (r ** (gamma - 1) / (gamma - 1) + 1.0 / r - gamma / (gamma - 1))
        return float(s.M[f] @ e)
    return energy


def test_drop_impact_smoke(tmp_path):
    """A water disc (R = 0.02 m, dx = 0.004 m) hitting a pool (0.2 × 0.05 m) at 5 m/s,
    c0 = 50 m/s, Monaghan α = 0.1, μ = 0.5 Pa s, run to 0.03 s (~900 steps; splash included).

    Measured: KE + PE ends 37 % below its start (viscous and artificial dissipation);
    including the Tait internal energy Σ M e(ρ), the total never rose more than 2.5e-8 of the
    initial kinetic energy above its start (round-off and the kdk time discretisation).
    History: with the library's condition limit 1e8 this run diverged at ~0.0164 s (a splash
    particle with 5 neighbours kept a near-singular linear fit whose large gradients made a
    mode stiffer than the h/c time step); the fluid's condition limit 100 sends such
    particles to Shepard and the run is stable (checked to 0.05 s)."""
    dx, R, U, Hp, W = 0.004, 0.02, 5.0, 0.05, 0.2
    c0 = 10.0 * U
    phases = [Phase("water", 1000.0, viscosity=0.5)]
    pool = FluidBody.block("pool", (0.0, 0.0), (W, Hp), dx, phases)
    pool.density[:] = TaitEOS(1000.0, c0).density(1000.0 * G * (Hp - pool.positions[:, 1]))
    yc = Hp + R + 4 * dx  # out of kernel reach of the pool at t = 0
    pts = lattice((W / 2 - R, yc - R), (W / 2 + R, yc + R), dx)
    disc = pts[np.linalg.norm(pts - [W / 2, yc], axis=1) < R]
    drop = FluidBody("drop", disc, dx, phases, velocity=(0.0, -U))
    walls = wall_box((0.0, 0.0), (W, 2 * Hp), dx, layers=3)
    effects = [TaitPressure(c0), Gravity(), Walls("free_slip"), MonaghanViscosity(0.1),
               NewtonianViscosity()]
    scene = Scene([pool, drop, walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=0.03, probes=[Probe("internal_energy", _tait_internal_energy(c0))])
    res = Simulation(scene).run(out=tmp_path, progress=False)  # raises if the watchdog fires
    s, ts = res.state.fluid, res.timeseries
    for arr in (s.x, s.v, s.rho, s.p):
        assert np.all(np.isfinite(arr))
    assert np.all(ts["total_mass"] == ts["total_mass"][0])
    ke0 = ts["kinetic_energy"][0]
    assert ke0 == pytest.approx(0.5 * drop.n * 1000.0 * dx**2 * U**2)
    E = ts["kinetic_energy"] + ts["potential_energy"]
    total = E + ts["internal_energy"]
    assert E[-1] < E[0]  # the impact dissipates (measured −37 % of KE0)
    # tolerance 1e-6 KE0: 40x the measured excursion, far below any physical energy change
    assert np.max(total - total[0]) < 1e-6 * ke0
    assert ts["max_density_ratio"].max() < 1.1 and ts["min_density_ratio"].min() > 0.9


@pytest.mark.slow
def test_long_hydrostatic_run_kinetic_energy_bounded(tmp_path):
    """10 s of the coarse tank (dx = 0.04 m, H = 0.4 m, ~14 500 steps): 9–11 s wall on an idle
    2-core machine, 33 s when the cores are shared (numba threads contend), hence ``slow``.

    Measured: KE peaks at 5.8e-6 M g H in the initial transient (t ≈ 0.2 s) and stays
    ~1e-6 M g H afterwards. Bound 1e-4 M g H: 17x the peak, and the level that the same tank
    without pair viscosity passes within 1 s on its way to diverging (see
    :func:`test_hydrostatic_without_pair_viscosity_is_not_long_time_stable`)."""
    res = Simulation(hydrostatic_tank(dx=0.04, t_end=10.0)).run(out=tmp_path, progress=False)
    ts = res.timeseries
    H = 0.4
    scale = float(ts["total_mass"][0]) * G * H
    ke = ts["kinetic_energy"]
    assert ke.max() < 1e-4 * scale
    late = ts["time"] > 5.0
    assert ke[late].max() < ke[~late].max()  # no growth in the second half
    s = res.state.fluid
    assert np.all((s.x[s.fluid, 0] > 0) & (s.x[s.fluid, 0] < 0.4) & (s.x[s.fluid, 1] > 0))


@pytest.mark.slow
@pytest.mark.parametrize("effects", [[], [BulkViscosity()]], ids=["no_viscosity", "bulk_viscosity"])
def test_hydrostatic_without_pair_viscosity_gains_energy(effects, tmp_path):
    """Documented finding: velocity modes with zero discrete divergence are invisible to the
    nodal-integrated pressure and to the bulk viscosity, so without the Monaghan pair viscosity
    the tank's kinetic energy grows (measured 1e-4 M g H at 1 s, 2e-3 at 3 s; diverges at ~5 s
    without, ~9 s with BulkViscosity) while the Monaghan tank stays below 6e-6 M g H."""
    scene = hydrostatic_tank(dx=0.04, t_end=3.0, effects=effects)
    res = Simulation(scene).run(out=tmp_path, progress=False)
    ts = res.timeseries
    scale = float(ts["total_mass"][0]) * G * 0.4
    assert ts["kinetic_energy"].max() > 1e-4 * scale
