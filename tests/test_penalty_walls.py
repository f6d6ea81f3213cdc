"""Rigid walls as penalty surfaces in the fluid solver (:class:`mlsgalerkin.fluid.PenaltyWalls`):
a hydrostatic column on a penalty floor, the wall force sensors against the weight of the fluid,
leaks stopped, the contact's time-step limit in the step, a moving wall's surface, a 3D tank,
bit-for-bit restart, and clear errors for bad parameters.

Numbers quoted in comments were measured with the defaults (α = 0.1, ζ = 0.03, g0 = Δx/2,
reach Δx; cubic spline, h = 1.3 Δx, linear MLS, KDK, lumped mass).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.contact import ContactSurface, penalty_forces, rigid_time_step
from mlsgalerkin.fluid import (
    DensityFilter,
    FluidBody,
    Gravity,
    MonaghanViscosity,
    PenaltyWalls,
    Phase,
    TaitEOS,
    TaitPressure,
    WallBody,
    Walls,
    wall_box,
)
from mlsgalerkin.fluid.penalty_walls import SurfaceOnlyWallWarning, sensor_columns
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.io import latest_checkpoint, load_checkpoint, read_timeseries
from mlsgalerkin.motion import Oscillation
from mlsgalerkin.scene import Output, Scene, SceneError
from mlsgalerkin.simulation import Simulation

G = 9.81
WATER = [Phase("water", 1000.0)]


def column(dx: float, H: float, W: float) -> FluidBody:
    """Water at hydrostatic rest (Tait density of ``ρ0 g (H − y)``), ``c0 = 10 √(2 g H)``."""
    fl = FluidBody.block("water", (0.0, 0.0), (W, H), dx, WATER)
    fl.density[:] = TaitEOS(1000.0, 10.0 * math.sqrt(2 * G * H)).density(1000.0 * G * (H - fl.positions[:, 1]))
    return fl


# ------------------------------------------------------------------ hydrostatic column
def test_hydrostatic_column_on_a_penalty_floor():
    """The tank of tests/test_fluid_solver.py (0.4 m × 0.4 m, Δx = 0.02 m, free-slip wall
    particles) with a penalty surface on its walls, 0.5 s. Measured: deepest penetration into
    the contact thickness 1.1e-4 Δx, nothing behind a wall surface, pressure RMS error 0.37 %
    of ρgH at the end (0.34 % without the penalty; after 2 s 0.61 % and 0.45 %). With a contact
    thickness of a whole spacing instead of half, the first row starts half a spacing inside it
    and is thrown off: 11.5 % RMS at 0.3 s, 0.5 Δx deep — the default thickness is what keeps
    the state at rest."""
    dx, H = 0.02, 0.4
    c0 = 10.0 * math.sqrt(2 * G * H)
    walls = wall_box((0.0, 0.0), (H, 1.5 * H), dx, layers=3, surface=True)
    effects = [TaitPressure(c0), Gravity(), Walls("free_slip"), PenaltyWalls(), MonaghanViscosity(0.1),
               DensityFilter(20)]
    res = Simulation(Scene([column(dx, H, H), walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=0.5)).run(progress=False)
    s, ts = res.state.fluid, res.timeseries
    f = s.fluid
    penetration = np.asarray(ts["penalty_max_penetration_dx"])
    assert penetration.max() < 0.05
    assert np.max(ts["max_wall_penetration_dx"]) == 0.0 and s.x[f, 1].min() > 0.49 * dx
    rms = math.sqrt(float(np.mean((s.p[f] - 1000.0 * G * (H - s.x[f, 1])) ** 2)))
    assert rms < 0.02 * 1000.0 * G * H
    assert rms < 0.005 * 1000.0 * G * H  # measured 0.37 %: the penalty does not disturb the rest state
    report = res.summary["fluid"]["effect_reports"]["penalty_walls"]
    assert report["max_penetration_dx"] == pytest.approx(penetration.max())
    assert report["thickness_m"] == 0.5 * dx and report["reach_m"] == dx
    json.dumps(report)


def test_wall_force_sensor_carries_the_weight_of_a_column_on_a_bare_surface():
    """A column in a tank that is only a penalty surface (no wall particles: warned, because the
    pressure next to it is off by tens of per cent, docs/theory/contact.md), 2 s: whatever the
    pressure does, momentum balance makes the time-averaged force on the walls the fluid's
    weight. Measured over 1–2 s: −1.0021 × the weight, horizontal force 0, moment about the
    origin (W/2)·F_y (the side walls' moments cancel)."""
    dx, H = 0.02, 0.2
    c0 = 10.0 * math.sqrt(2 * G * H)
    tank = wall_box((0.0, 0.0), (H, 1.5 * H), dx, layers=0, surface=True)
    assert tank.n == 0 and tank.surface is not None
    effects = [TaitPressure(c0), Gravity(), PenaltyWalls(), MonaghanViscosity(0.1), DensityFilter(20)]
    with pytest.warns(SurfaceOnlyWallWarning, match="only a penalty surface"):
        res = Simulation(Scene([column(dx, H, H), tank], [FluidScheme(effects, stabilisation="as_listed")], t_end=2.0)).run(progress=False)
    ts = res.timeseries
    assert set(sensor_columns("walls", 2)) <= set(ts) and sensor_columns("walls", 2)[-1] == "wall_moment_walls"
    t = np.asarray(ts["time"])
    w = np.diff(t, prepend=0.0) * (t > 1.0)

    def mean(col):
        return float(np.sum(np.asarray(ts[col]) * w) / np.sum(w))

    weight = float(np.sum(res.state.fluid.M[res.state.fluid.fluid])) * G
    assert mean("wall_force_y_walls") == pytest.approx(-weight, rel=0.01)
    assert abs(mean("wall_force_x_walls")) < 1e-3 * weight
    assert mean("wall_moment_walls") == pytest.approx(0.5 * H * mean("wall_force_y_walls"), rel=0.01)
    assert np.max(ts["penalty_max_penetration_dx"]) < 0.1  # measured 0.048
    rec = res.summary["fluid"]["effect_reports"]["penalty_walls"]["walls"]["walls"]
    assert rec["peak_force"] >= weight and rec["time_of_peak_force_s"] > 0


def test_sensor_columns_are_the_kernel_reaction_at_that_evaluation():
    """The sensors of the last evaluation, recomputed from the state with the kernel: the total
    reaction and its moment about the given point. (The evaluation at the end of a KDK step
    sees the half-step velocity ``v − ½Δt a``.)"""
    dx = 0.01
    water = FluidBody.block("water", (0.02, 0.0), (0.12, 0.06), dx, WATER, velocity=(-0.5, -0.5))
    walls = wall_box((0.0, 0.0), (0.2, 0.2), dx, layers=3, surface=True)
    pw = PenaltyWalls(moment_about={"walls": (0.1, 0.05)})
    sim = Simulation(Scene([water, walls], [FluidScheme([TaitPressure(20.0), Gravity(), Walls(), pw], stabilisation="as_listed")], t_end=0.02))
    res = sim.run(progress=False)
    s = res.state.fluid
    f = s.fluid
    surf = s.wall_surfaces["walls"]
    v_half = s.v[f] - 0.5 * res.state.dt * s.a[f]
    ref = penalty_forces(s.x[f], v_half, s.M[f], surf.x, surf.v, None, surf.facets, dt_ref=pw.summary()["dt_ref_s"],
                         thickness=0.5 * dx, reach=dx, centre=(0.1, 0.05))
    assert ref.contacts > 0 and s.sensors["penalty_contacts"] == ref.contacts
    sensed = [s.sensors[c] for c in sensor_columns("walls", 2)]
    np.testing.assert_allclose(sensed, [*ref.total_force, ref.moment], rtol=1e-9)
    assert s.sensors["penalty_max_penetration_dx"] == pytest.approx(ref.max_penetration / dx, rel=1e-12)
    assert res.timeseries["wall_force_x_walls"][-1] == s.sensors["wall_force_x_walls"]


def test_penalty_walls_stop_a_leak():
    """A block of water thrown at 8 m/s (Mach 0.27) onto the floor of a tank 0.4 m tall: the wall
    particles alone let two particles into the floor, the deepest 0.61 Δx behind its surface;
    with the penalty surface none gets behind it, the deepest is 0.30 Δx into the contact
    thickness. (At 6 m/s in a tank 0.2 m tall no particle got into a wall: the two the plain
    half-space test counted, 0.07 Δx "behind", had splashed over the top of the end wall.)"""
    def run(penalty):
        dx = 0.01
        water = FluidBody.block("water", (0.05, 0.02), (0.15, 0.07), dx, WATER, velocity=(0.0, -8.0))
        walls = wall_box((0.0, 0.0), (0.2, 0.4), dx, layers=3, surface=penalty)
        effects = [TaitPressure(30.0), Gravity(), Walls(), MonaghanViscosity(0.05)] + ([PenaltyWalls()] if penalty
                                                                                        else [])
        return Simulation(Scene([water, walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=0.03)).run(progress=False).timeseries

    leaky, held = run(False), run(True)
    assert np.max(leaky["max_wall_penetration_dx"]) > 0.3 and np.max(leaky["wall_penetrations"]) >= 1
    assert np.max(held["max_wall_penetration_dx"]) == 0.0 and np.max(held["wall_penetrations"]) == 0
    assert 0.05 < np.max(held["penalty_max_penetration_dx"]) < 0.5


def test_a_block_falls_into_a_3d_tank_surface():
    """The same API in 3D: a 5×5×5 block falling into a tank of 10 triangles; nothing gets
    through the floor, the sensor has three force and three moment columns."""
    water = FluidBody.block("water", (0.02, 0.02, 0.03), (0.12, 0.12, 0.13), 0.02, WATER, velocity=(0, 0, -1.0))
    box = WallBody("box", surface=ContactSurface.tank((0, 0, 0), (0.14, 0.14, 0.3)))
    with pytest.warns(SurfaceOnlyWallWarning):
        res = Simulation(Scene([water, box], [FluidScheme([TaitPressure(20.0), Gravity((0, 0, -G)), PenaltyWalls(),
                                              MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=0.05)).run(progress=False)
    ts = res.timeseries
    assert set(sensor_columns("box", 3)) <= set(ts)
    assert np.max(ts["wall_force_z_box"]) <= 0 < -np.min(ts["wall_force_z_box"])  # pushed down, never pulled up
    s = res.state.fluid
    assert s.x[s.fluid, 2].min() > 0.0 and np.max(ts["penalty_max_penetration_dx"]) < 0.5  # measured 0.17


# ------------------------------------------------------------------ time step
def test_the_contact_time_step_limit_joins_the_minimum():
    """With ``dt_ref`` far below the fluid's own step, the contact's limit
    ``C · 2(√(1+ζ²) − ζ) Δt_ref/√(d α)`` (times the scene's safety) is the step."""
    dx = 0.01
    water = FluidBody.block("water", (0.0, 0.0), (0.1, 0.05), dx, WATER)
    walls = wall_box((0.0, 0.0), (0.1, 0.1), dx, layers=3, surface=True)
    pw = PenaltyWalls(dt_ref=2e-6, alpha=0.05, damping=0.1)
    res = Simulation(Scene([water, walls], [FluidScheme([TaitPressure(10.0), Gravity(), Walls(), pw], safety=0.9, stabilisation="as_listed")], t_end=2e-4)).run(progress=False)
    expected = 0.9 * rigid_time_step(0.05, 0.1, 2e-6, 2)
    assert expected == pytest.approx(0.9 * 0.5 * 2 * (math.sqrt(1.01) - 0.1) * 2e-6 / math.sqrt(0.1))
    dts = np.asarray(res.timeseries["dt"])
    assert len(dts) > 30  # 2e-4 s in steps of 5.2e-6 s (the fluid alone would take 2.5e-4 s steps)
    np.testing.assert_allclose(dts[1:-1], expected, rtol=1e-14)
    assert res.summary["fluid"]["effect_reports"]["penalty_walls"]["time_step_limit_s"] == expected / 0.9
    # by default the reference step is the fluid's first step and the contact never binds
    free = Simulation(Scene([water, wall_box((0.0, 0.0), (0.1, 0.1), dx, layers=3, surface=True)], [FluidScheme([TaitPressure(10.0), Gravity(), Walls(), PenaltyWalls()], stabilisation="as_listed")], t_end=2e-3)).run(progress=False)
    rep = free.summary["fluid"]["effect_reports"]["penalty_walls"]
    assert rep["dt_ref_s"] == free.timeseries["dt"][1] and rep["time_step_limit_s"] > 2 * rep["dt_ref_s"]


# ------------------------------------------------------------------ moving wall
def test_a_moving_walls_surface_follows_its_motion():
    dx = 0.01
    motion = Oscillation(stroke=0.02, period=0.05)
    water = FluidBody.block("water", (0.03, 0.0), (0.13, 0.05), dx, WATER)
    paddle = WallBody("paddle", surface=ContactSurface.polyline([(0.02, -0.01), (0.02, 0.1)]), motion=motion)
    walls = wall_box((0.0, 0.0), (0.2, 0.1), dx, layers=3, surface=True)
    with pytest.warns(SurfaceOnlyWallWarning, match="paddle"):
        res = Simulation(Scene([water, walls, paddle], [FluidScheme([TaitPressure(20.0), Gravity(), Walls(), PenaltyWalls()], stabilisation="as_listed")], t_end=0.02)).run(progress=False)
    s = res.state.fluid
    surf = s.wall_surfaces["paddle"]
    np.testing.assert_allclose(surf.x, motion.positions(paddle.surface.nodes, s.t), rtol=0, atol=1e-15)
    np.testing.assert_allclose(surf.v, motion.velocities(paddle.surface.nodes, s.t), rtol=0, atol=1e-15)
    assert np.max(np.abs(res.timeseries["wall_force_x_paddle"])) > 0  # the paddle pushed the water
    np.testing.assert_array_equal(s.wall_surfaces["walls"].x, walls.surface.nodes)  # fixed walls stay


# ------------------------------------------------------------------ restart
def _falling_scene() -> Scene:
    dx, c0 = 0.02, 20.0
    water = FluidBody.block("water", (0.0, 0.02), (0.2, 0.12), dx, WATER, velocity=(0.4, -4.0))
    walls = wall_box((0.0, 0.0), (0.4, 0.4), dx, layers=3, surface=True)
    effects = [TaitPressure(c0), Gravity(), Walls("free_slip"), PenaltyWalls(moment_about=(0.2, 0.0)),
               MonaghanViscosity(0.1), DensityFilter(5)]
    return Scene([water, walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=0.06, output=Output(checkpoint_every=0.015))


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("penalty_uninterrupted")
    res = Simulation(_falling_scene()).run(out=out, progress=False)
    assert res.summary["steps"] > 100 and np.count_nonzero(res.timeseries["penalty_contacts"]) > 100  # from step 25
    return res, out


def _assert_same_run(a, b, dir_a: Path, dir_b: Path) -> None:
    for k in ("x", "v", "rho", "p", "M", "a"):
        assert np.array_equal(getattr(a.state.fluid, k), getattr(b.state.fluid, k)), k
    assert a.state.step == b.state.step and a.state.t == b.state.t
    assert a.state.fluid.sensors == b.state.fluid.sensors
    ta, tb = read_timeseries(dir_a / "timeseries.csv"), read_timeseries(dir_b / "timeseries.csv")
    assert list(ta) == list(tb) and "wall_force_y_walls" in ta
    for k in ta:
        assert np.array_equal(ta[k], tb[k]), k
    assert a.summary["fluid"]["effect_reports"] == b.summary["fluid"]["effect_reports"]


def test_restart_with_penalty_walls_is_bit_for_bit(uninterrupted, tmp_path):
    ref, ref_dir = uninterrupted
    part = Simulation(_falling_scene()).run(out=tmp_path, progress=False, max_steps=61)
    assert part.state.step == 61
    meta = load_checkpoint(latest_checkpoint(tmp_path / "checkpoints"))[1]
    saved = meta["solvers"]["fluid"]["effects"]["penalty_walls"]
    assert saved["dt_ref"] == ref.summary["fluid"]["effect_reports"]["penalty_walls"]["dt_ref_s"]
    res = Simulation(_falling_scene()).run(out=tmp_path, restart="latest", progress=False)
    _assert_same_run(ref, res, ref_dir, tmp_path)


def test_restart_from_a_periodic_checkpoint_with_penalty_walls_is_bit_for_bit(uninterrupted, tmp_path):
    ref, ref_dir = uninterrupted
    Simulation(_falling_scene()).run(out=tmp_path, progress=False, max_steps=90)
    latest_checkpoint(tmp_path / "checkpoints").unlink()  # a crash loses the checkpoint at the end
    assert load_checkpoint(latest_checkpoint(tmp_path / "checkpoints"))[1]["step"] < 90
    res = Simulation(_falling_scene()).run(out=tmp_path, restart="latest", progress=False)
    _assert_same_run(ref, res, ref_dir, tmp_path)


# ------------------------------------------------------------------ bad input
def _water():
    return FluidBody.block("water", (0.0, 0.0), (0.1, 0.05), 0.01, WATER)


def _box(**kw):
    return wall_box((0.0, 0.0), (0.2, 0.1), 0.01, **kw)


def _scene(effect=None, bodies=None):
    bodies = [_water(), _box(surface=True)] if bodies is None else bodies
    return Scene(bodies, [FluidScheme([TaitPressure(10.0), Walls(), effect or PenaltyWalls()], stabilisation="as_listed")], t_end=0.1)


BAD_SCENES = [
    ("alpha negative", lambda: _scene(PenaltyWalls(alpha=-0.1)), "alpha (the stiffness factor"),
    ("alpha above one", lambda: _scene(PenaltyWalls(alpha=4.0)), "keep alpha <= 1"),
    ("alpha text", lambda: _scene(PenaltyWalls(alpha="0.1")), "alpha"),
    ("damping one", lambda: _scene(PenaltyWalls(damping=1.0)), "damping (ζ, a fraction of critical damping)"),
    ("thickness negative", lambda: _scene(PenaltyWalls(thickness=-0.005)), "thickness (the contact thickness g0"),
    ("reach below thickness", lambda: _scene(PenaltyWalls(thickness=0.005, reach=0.004)), "must exceed the thickness"),
    ("reach nan", lambda: _scene(PenaltyWalls(reach=float("nan"))), "reach"),
    ("dt_ref zero", lambda: _scene(PenaltyWalls(dt_ref=0.0)), "dt_ref (the reference time step"),
    ("feature angle", lambda: _scene(PenaltyWalls(feature_angle=180.0)), "feature_angle must be in (0, 90]"),
    ("moment point 3D", lambda: _scene(PenaltyWalls(moment_about=(0, 0, 0))), "moment_about for all walls must be"),
    ("moment of an unknown wall", lambda: _scene(PenaltyWalls(moment_about={"lid": (0, 0)})),
     "moment_about names 'lid'"),
    ("no surface to touch", lambda: _scene(bodies=[_water(), _box()]), "no wall body has a penalty surface"),
    ("surface without the effect", lambda: Scene([_water(), _box(surface=True)], [FluidScheme([TaitPressure(10.0), Walls()], stabilisation="as_listed")], t_end=0.1), "list PenaltyWalls()"),
    ("surface-only wall with Walls only", lambda: Scene([_water(), _box(layers=0, surface=True)], [FluidScheme([TaitPressure(10.0), Walls()], stabilisation="as_listed")], t_end=0.1),
     "a wall of only a penalty surface needs PenaltyWalls"),
    ("fluid behind the surface", lambda: Scene([
        FluidBody.block("water", (0.0, -0.02), (0.1, 0.05), 0.01, WATER),
        WallBody("floor", surface=ContactSurface.polyline([(0.3, 0.0), (-0.1, 0.0)]))], [FluidScheme([TaitPressure(10.0), PenaltyWalls()], stabilisation="as_listed")], t_end=0.1), "start behind the penalty surface of wall body 'floor'"),
    ("3D surface in a 2D scene", lambda: _scene(bodies=[_water(), _box(), WallBody(
        "lid", surface=ContactSurface.tank((0, 0, 0), (1, 1, 1)))]), "bodies mix dimensions [2, 3]"),
]


@pytest.mark.parametrize("name, make, fragment", BAD_SCENES, ids=[c[0] for c in BAD_SCENES])
def test_bad_penalty_wall_scenes_are_refused_before_any_work(name, make, fragment):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SurfaceOnlyWallWarning)
        with pytest.raises(SceneError) as info:
            Simulation(make())
    assert fragment in str(info.value), str(info.value)


@pytest.mark.parametrize("make, fragment", [
    (lambda: WallBody("w", surface="tank"), "surface must be a mlsgalerkin.contact.ContactSurface"),
    (lambda: WallBody("w"), "give wall particles (positions and spacing), a penalty surface"),
    (lambda: WallBody("w", np.zeros((2, 2))), "spacing must be positive"),
    (lambda: WallBody("w", surface=ContactSurface.polyline([(0, 0), (1, 0)]), normals=np.zeros((1, 2))),
     "normals belong to wall particles"),
    (lambda: WallBody("w", np.zeros((1, 3)), 0.01, surface=ContactSurface.polyline([(0, 0), (1, 0)])),
     "its penalty surface is 2D but its particles are 3D"),
    (lambda: wall_box((0, 0), (1, 1), 0.1, layers=0), "layers=0 with surface=True"),
])
def test_bad_wall_bodies_are_refused_with_the_reason(make, fragment):
    with pytest.raises(ValueError) as info:
        make()
    assert fragment in str(info.value)
