"""Structures in the run loop (:mod:`mlsgalerkin.structure.solver`): the spring-hinged rigid beam's dry
period, the clamped elastic beam's first period with explicit sub-cycling and with Newmark,
energy of undamped free vibration, the compiled sub-cycle against its numpy reference, the
nonlinear model in the loop, restarts, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshQuad

from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.scene import Probe, Scene, SceneError
from mlsgalerkin.simulation import Simulation
from mlsgalerkin.structure import ElasticBody, ElasticMaterial, Hinge, RigidBody
from mlsgalerkin.structure.explicit import subcycle_linear, subcycle_linear_reference
from mlsgalerkin.structure.scheme import StructureScheme

#: The clamped beam of the dam break on an elastic wall (Sun 2016): E = 0.2 GPa, 6 mm thick,
#: 47.16 kg/m (ρ = 7860 kg/m³), 0.304 m long; Euler–Bernoulli first period 0.5977 s (0.5971 s quoted).
L, H, E, RHO = 0.304, 0.006, 0.2e9, 47.16 / 0.006


def crossings(t, y):
    """Times where ``y`` crosses zero upward (linear interpolation)."""
    t, y = np.asarray(t), np.asarray(y)
    k = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def hinged_beam(**kw):
    return RigidBody.beam("beam", base=(3.22, 0.0), length=2.0, mass=1.0, thickness=0.02,
                          constraint=Hinge((3.22, 0.0), stiffness=1500.0), gravity=(0.0, -9.81), **kw)


def test_spring_hinged_rigid_beam_dry_period():
    """I θ'' + (K − m g L/2) θ = 0 with I = m(L² + t²)/12 + m(L/2)²: T = 0.1879 s (Sun 2016) within 1 %
    (measured −0.005 % at Δt = 1 ms, 20 sub-steps of ω δt ≤ 0.05); energy within 0.1 %."""
    beam = hinged_beam()
    beam.angular_velocity = 0.1
    res = Simulation(Scene([beam], [StructureScheme(dt_max=1e-3)], t_end=1.0)).run(progress=False)
    ts = res.timeseries
    period = np.diff(crossings(ts["time"], ts["beam_angle"])).mean()
    assert abs(period - 0.1879) < 0.01 * 0.1879
    e = np.asarray(ts["beam_kinetic_energy"]) + np.asarray(ts["beam_spring_energy"]) + np.asarray(ts["beam_weight_potential"])
    assert np.ptp(e) < 1e-3 * e[0]
    assert max(np.abs(ts["beam_angle"])) == pytest.approx(0.1 / (2 * np.pi / 0.1879), rel=0.02)


def clamped_beam(integrator="explicit", ny=38, high_mode_damping=0.0):
    mesh = MeshQuad.init_tensor(np.linspace(0.0, H, 2), np.linspace(0.0, L, ny + 1))
    return ElasticBody("wall", mesh, ElasticMaterial(E, 0.3, RHO, plane="stress"), integrator=integrator,
                       high_mode_damping=high_mode_damping,
                       clamped=lambda x: np.isclose(x[1], 0.0), wet=lambda x: np.isclose(x[0], 0.0),
                       points={"tip": (0.0, L)})


@pytest.mark.parametrize("integrator, dt", [("explicit", 2e-3), ("newmark", 2e-3)])
def test_clamped_beam_free_vibration_period_and_energy(integrator, dt):
    """Released from a static tip deflection, the undamped beam swings with its first period
    (0.5971 s, within 2 %; plane stress maps the 2D body to the beam) and keeps kinetic + strain
    energy within 0.5 % over 10 periods: explicit with sub-cycling inside each outer step, and
    implicit Newmark (average acceleration conserves energy exactly for a linear system)."""
    b = clamped_beam(integrator)
    sim = Simulation(Scene([b], [StructureScheme(dt_max=dt)], t_end=6.0))
    m = sim.solver("structure").state.body("wall")
    m.u[:] = b.static(b.edge_traction(lambda x: np.isclose(x[1], L), (10.0 / H, 0.0)))
    res = sim.run(progress=False)
    ts = res.timeseries
    period = np.diff(crossings(ts["time"], ts["wall_tip_ux"])).mean()
    assert abs(period - 0.5971) < 0.02 * 0.5971
    e = np.asarray(ts["wall_kinetic_energy"]) + np.asarray(ts["wall_strain_energy"])
    assert np.ptp(e) < 5e-3 * e[0]
    body = res.summary["structure"]["bodies"]["wall"]
    if integrator == "explicit":
        assert body["substeps_per_step_max"] > 10    # sub-cycled: the outer step is far above the limit
    else:
        assert body["substeps"] == body["outer_steps"]


def test_compiled_subcycle_agrees_with_the_numpy_reference():
    b = clamped_beam()
    rng = np.random.default_rng(3)
    n = b.n_dofs
    K = b.stiffness.tocsr()
    inv_m = 1.0 / b.lumped_mass
    fixed = np.zeros(n, dtype=bool)
    fixed[b.clamped_dofs] = True
    f = rng.normal(size=n)
    start = [rng.normal(scale=1e-4, size=n) * ~fixed for _ in range(3)]
    one = [x.copy() for x in start]
    two = [x.copy() for x in start]
    dt = 0.5 * b.stable_time_step()
    df = rng.normal(size=n)
    subcycle_linear(K, inv_m, fixed, f, df, *one, dt, 25, 0.5, 1e-6)
    subcycle_linear_reference(K, inv_m, fixed, f, df, *two, dt, 25, 0.5, 1e-6)
    for x, y in zip(one, two):
        np.testing.assert_allclose(x, y, rtol=1e-10, atol=1e-12 * np.abs(y).max())
    assert np.all(one[0][fixed] == 0)


def test_nonlinear_cantilever_under_its_weight_settles_near_the_linear_answer():
    """A stiff cantilever sagging under its own weight (tip deflection 0.2 % of its length) with
    St Venant–Kirchhoff and Rayleigh mass damping settles within 1 % of the linear static answer."""
    mesh = MeshQuad.init_tensor(np.linspace(0.0, 1.0, 21), np.linspace(0.0, 0.1, 3))
    kw = {"clamped": lambda x: np.isclose(x[0], 0.0), "gravity": (0.0, -9.81), "points": {"tip": (1.0, 0.05)}}
    mat = ElasticMaterial(1e8, 0.3, 1000.0, plane="strain")
    lin = ElasticBody("lin", mesh, mat, **kw)
    static = lin.point_displacements(lin.static(lin.weight))["tip"][1]
    omega1 = 3.5160 * np.sqrt(1e8 / (1 - 0.09) * 0.1**2 / 12 / 1000.0)   # first bending frequency (rad/s)
    body = ElasticBody("beam", mesh, mat, model="stvenant_kirchhoff", damping=(1.2 * omega1, 0.0), **kw)
    res = Simulation(Scene([body], [StructureScheme(dt_max=1e-3)], t_end=0.3)).run(progress=False)
    tip = res.timeseries["beam_tip_uy"][-1]
    assert abs(static) > 1e-3 and abs(tip - static) < 0.01 * abs(static)


def test_structure_restart_continues_bit_for_bit(tmp_path):
    def scene():
        beam = hinged_beam()
        beam.angular_velocity = 0.2
        return Scene([beam, clamped_beam()], [StructureScheme(dt_max=1e-3)], t_end=0.05)

    straight = Simulation(scene()).run(progress=False)
    Simulation(scene()).run(out=tmp_path, progress=False, max_steps=17)
    resumed = Simulation(scene()).run(out=tmp_path, progress=False, restart="latest")
    for name in ("beam", "wall"):
        a = straight.state.systems["structure"].body(name).observables()
        b = resumed.state.systems["structure"].body(name).observables()
        assert a == b
    assert (tmp_path / "structure.pvd").is_file()


def test_bad_structure_input_is_refused_clearly():
    with pytest.raises(SceneError, match=r"needs an outer time step: list StructureScheme\(dt_max=...\)"):
        Simulation(Scene([hinged_beam()], [], t_end=0.1))
    mesh = MeshQuad.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    mat = ElasticMaterial(1e7, 0.3, 1000.0)
    with pytest.raises(ValueError, match="wet predicate selects no boundary facet"):
        ElasticBody("b", mesh, mat, wet=lambda x: x[0] > 5.0)
    with pytest.raises(ValueError, match="explicit integrator only"):
        ElasticBody("b", mesh, mat, model="neo_hookean", integrator="newmark")
    with pytest.raises(ValueError, match="plane strain"):
        ElasticBody("b", mesh, ElasticMaterial(1e7, 0.3, 1000.0, plane="stress"), model="neo_hookean")
    with pytest.raises(ValueError, match="outside the mesh"):
        ElasticBody("b", mesh, mat, points={"far": (3.0, 3.0)})
    with pytest.raises(SceneError, match="Newmark needs a clamped boundary"):
        Simulation(Scene([ElasticBody("b", mesh, mat, integrator="newmark")], [StructureScheme(dt_max=1e-3)], t_end=0.1))
    square = ContactSurface.polyline([(0, 0), (1, 0), (1, 1), (0, 1), (0, 0)])
    with pytest.raises(ValueError, match="mass must be positive"):
        RigidBody("r", square, 0.0, 1.0, (0.5, 0.5))
    with pytest.raises(ValueError, match="does not hold the body up"):
        RigidBody.beam("b", (0, 0), 2.0, 1.0, 0.02, constraint=Hinge((0, 0), stiffness=5.0), gravity=(0, -9.81))
    with pytest.raises(ValueError, match="constraint must be one of"):
        RigidBody("r", square, 1.0, 1.0, (0.5, 0.5), constraint="sliding")


def test_a_probe_reads_a_body_by_name():
    """``state.body(name)`` is the public way for a probe to read a structure (elastic: ``u``, ``v``;
    rigid: ``X``, ``V``, ``theta``, ``F``); an unknown name says which bodies have a live state."""
    beam = hinged_beam()
    beam.angular_velocity = 0.1
    seen = []
    probe = Probe("angle_read", lambda state: seen.append(state.body("beam").theta) or seen[-1])
    res = Simulation(Scene([beam], [StructureScheme(dt_max=1e-3)], t_end=0.01, probes=[probe])).run(progress=False)
    assert np.array_equal(res.timeseries["angle_read"], res.timeseries["beam_angle"])
    with pytest.raises(KeyError, match=r"no body 'nope' with a live state in this run; bodies with one: \['beam'\]"):
        res.state.body("nope")
