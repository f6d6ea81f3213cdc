"""Elastic bodies in 3D with the same API (:mod:`mlsgalerkin.structure.elastic`): hexahedra and
tetrahedra against beam theory, the oriented triangles of the wet surface, and a 3D water block
landing on a clamped plate through node-to-surface penalty contact."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshHex, MeshTet

from mlsgalerkin.fluid import FluidBody, Gravity, MonaghanViscosity, Phase, TaitPressure
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.interactions import PenaltyContact
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation
from mlsgalerkin.structure import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.scheme import StructureScheme

L, H, E, P = 1.0, 0.1, 1e7, 10.0


@pytest.mark.parametrize("element, mesh, tol", [
    ("Hex2", MeshHex.init_tensor(np.linspace(0, L, 21), np.linspace(0, H, 2), np.linspace(0, H, 2)), 0.005),
    ("Hex1", MeshHex.init_tensor(np.linspace(0, L, 41), np.linspace(0, H, 5), np.linspace(0, H, 5)), 0.04),
])
def test_3d_cantilever_tip_deflection_against_timoshenko(element, mesh, tol):
    """δ = P L³/(3 E I) + P L/(κ G A) for a square 0.1 m section, ν = 0, a shear traction on the
    free end. Measured: 27-node Hex2 −0.10 %, Hex1 −3.1 % (shear locking of the linear brick;
    linear tetrahedra lock worse, −18 % on the same grid)."""
    b = ElasticBody("c", mesh, ElasticMaterial(E, 0.0, 1000.0), element, clamped=lambda x: np.isclose(x[0], 0.0))
    assert b.dim == 3
    u = b.static(b.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / H**2, 0.0)))
    tip = b.displacement_at(np.array([[L], [H / 2], [H / 2]]), u)[0, 1]
    ref = -(P * L**3 / (3 * E * H**4 / 12) + P * L / (5 / 6 * E / 2 * H**2))
    assert abs(tip / ref - 1.0) < tol


def test_3d_wet_surface_is_triangles_facing_out_of_the_body():
    mesh = MeshTet.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3), np.linspace(0, 0.1, 2))
    b = ElasticBody("box", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "P1")
    surf = b.surface()
    assert surf.dim == 3 and surf.facets.shape[1] == 3
    side = np.einsum("ij,ij->i", surf.normals(), surf.centroids() - np.array([0.2, 0.1, 0.05]))
    assert np.all(side > 0)
    top = b.surface(lambda x: np.isclose(x[2], 0.1))
    assert np.allclose(top.normals(), [0.0, 0.0, 1.0]) and np.isclose(top.measures().sum(), 0.4 * 0.2)


def test_a_3d_water_block_lands_on_a_clamped_plate():
    """216 particles fall 5 mm onto a clamped Hex1 plate: penalty contact holds every particle above
    the plate and pushes the plate down."""
    dx = 0.01
    mesh = MeshHex.init_tensor(np.linspace(0, 0.2, 9), np.linspace(0, 0.2, 9), np.linspace(-0.01, 0.0, 2))
    edge = lambda x: np.isclose(x[0], 0) | np.isclose(x[0], 0.2) | np.isclose(x[1], 0) | np.isclose(x[1], 0.2)
    plate = ElasticBody("plate", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "Hex1", clamped=edge,
                        wet=lambda x: np.isclose(x[2], 0.0), points={"mid": (0.1, 0.1, -0.005)})
    water = FluidBody.block("water", (0.07, 0.07, 0.005), (0.13, 0.13, 0.065), dx, [Phase("water", 1000.0)])
    scene = Scene([water, plate], [FluidScheme([TaitPressure(10.0), Gravity((0.0, 0.0, -9.81)), MonaghanViscosity(0.1)], stabilisation="as_listed")], t_end=0.1, interactions=[PenaltyContact("water", "plate", thickness=0.5 * dx)])
    res = Simulation(scene).run(progress=False)
    ts = res.timeseries
    assert res.summary["status"] == "completed"
    assert res.state.fluid.x[:, 2].min() > 0.0
    late = np.asarray(ts["time"]) > 0.07
    assert np.all(np.asarray(ts["plate_force_z"])[late] < 0.0)
    assert np.mean(np.asarray(ts["plate_mid_uz"])[late]) < 0.0


def _box(lo, hi):
    """A closed box surface of 12 triangles, normals out."""
    from mlsgalerkin.contact import ContactSurface

    inner = ContactSurface.tank(lo, hi, open_top=False)
    return inner.flipped()


def test_3d_rigid_body_on_a_hinge_swings_with_its_dry_period():
    """A 3D plank standing on a hinge whose axis is the x axis, gravity along −z: the same
    ``ω² = (K + m g·r⊥)/I_p`` as in 2D; the run loop's period within 0.5 %."""
    from mlsgalerkin.structure import Hinge, RigidBody

    m, L, t = 2.0, 1.0, 0.05
    plank = RigidBody("plank", _box((-0.1, -t / 2, 0.0), (0.1, t / 2, L)), m, m * (L**2 + t**2) / 12.0,
                      (0.0, 0.0, L / 2), constraint=Hinge((0.0, 0.0, 0.0), stiffness=200.0, axis=(1.0, 0.0, 0.0)),
                      gravity=(0.0, 0.0, -9.81), angular_velocity=0.1)
    expected = 2 * np.pi / np.sqrt((200.0 - m * 9.81 * L / 2) / (m * (L**2 + t**2) / 12 + m * (L / 2) ** 2))
    assert plank.natural_period() == pytest.approx(expected, rel=1e-12)
    res = Simulation(Scene([plank], [StructureScheme(dt_max=expected / 200)], t_end=3 * expected)).run(progress=False)
    ts = res.timeseries
    t_, a = np.asarray(ts["time"]), np.asarray(ts["plank_angle"])
    k = np.flatnonzero((a[:-1] < 0) & (a[1:] >= 0))
    crossings = t_[k] - a[k] * (t_[k + 1] - t_[k]) / (a[k + 1] - a[k])
    assert np.diff(crossings).mean() == pytest.approx(expected, rel=5e-3)
    # it turns about x: the top moves in y and z, never in x
    top = res.state.systems["structure"].body("plank").nodes()
    assert np.allclose(top[:, 0], plank.surface.nodes[:, 0])


def test_3d_rigid_body_falls_vertically():
    from mlsgalerkin.structure import RigidBody

    box = RigidBody("box", _box((0, 0, 1.0), (0.2, 0.2, 1.2)), 5.0, 0.1, (0.1, 0.1, 1.1), constraint="vertical",
                    gravity=(0.0, 0.0, -9.81))
    res = Simulation(Scene([box], [StructureScheme(dt_max=1e-3)], t_end=0.2)).run(progress=False)
    body = res.state.systems["structure"].body("box")
    assert body.V == pytest.approx([0.0, 0.0, -9.81 * 0.2], abs=1e-9)
    assert body.c[2] - 1.1 == pytest.approx(-0.5 * 9.81 * 0.2**2, rel=1e-6)
    # free rotation in 3D is built (the free-body tests below): the same call gives a 6-dof body
    assert RigidBody("b", _box((0, 0, 0), (1, 1, 1)), 1.0, 1.0, (0.5, 0.5, 0.5), constraint="free").free_rotation


# ---------------------------------------------------------------------- free rigid bodies in 3D
def _free_box(inertia, angular_velocity, name="top", **kw):
    """A free rigid box (0.6 × 0.4 × 0.2 m, 1 kg, centre at the origin) with the given inertia
    (the box's own shape does not enter the dynamics: only its mass and inertia do)."""
    from mlsgalerkin.structure import RigidBody

    return RigidBody(name, _box((-0.3, -0.2, -0.1), (0.3, 0.2, 0.1)), 1.0, inertia, (0.0, 0.0, 0.0),
                     constraint="free", angular_velocity=angular_velocity, **kw)


def _couple(motion, moment_z):
    """Forces ``f_a = k e_z × r_a`` on the surface nodes, ``r_a`` from the centre: no resultant
    (the box's nodes are symmetric about its centre) and the moment ``moment_z e_z`` (N m)
    about the centre, ``k = M/Σ|r_a⊥|²``."""
    r = motion.nodes() - motion.c
    k = moment_z / np.sum(r[:, 0] ** 2 + r[:, 1] ** 2)
    return k * np.stack([-r[:, 1], r[:, 0], np.zeros(len(r))], axis=1)


def test_free_3d_asymmetric_top_keeps_its_energy_and_angular_momentum():
    """A torque-free top with principal moments 1, 2, 3 kg m² spun near its intermediate axis
    (ω0 = (0.01, 1, 0.01) rad/s body = world frame at rest): it tumbles, the spin about y
    changing sign (Dzhanibekov's flips), over 10⁴ steps of 0.01 s (100 s, |ω|Δt = 0.01). The
    splitting keeps the world angular momentum exactly (each sub-flow turns the body about an
    axis and leaves L fixed): rebuilt from the orientation and the body-frame ω,
    ``R I Ω = L0`` within 1e-13 (measured 1.8e-15); the kinetic energy oscillates within
    2e-6 (measured 6.9e-7, O(Δt²)) without drift (the means over the first and the last 1000
    steps differ by 1.5e-9 of E0, asserted below 1e-7; a linear fit gives −1.7e-10 per 100 s);
    the rotation matrix stays orthonormal with det 1 to 1e-12 (measured 2e-15)."""
    from mlsgalerkin.structure.steppers import FreeRigidMotion
    from mlsgalerkin.structure.steppers.rotation import quaternion_matrix

    J = np.array([1.0, 2.0, 3.0])
    m = FreeRigidMotion(_free_box(J, (0.01, 1.0, 0.01)))
    m.start()
    E0, L0 = m.kinetic_energy(), m.L.copy()
    energy, spin_y, L_err, orth = [], [], 0.0, 0.0
    for _ in range(10_000):
        m.advance(0.01)
        R = quaternion_matrix(m.q)
        w_body = m.body_angular_velocity()
        energy.append(m.kinetic_energy())
        spin_y.append(w_body[1])
        L_err = max(L_err, np.abs(R @ (J * w_body) - L0).max() / np.linalg.norm(L0))
        orth = max(orth, np.abs(R.T @ R - np.eye(3)).max(), abs(np.linalg.det(R) - 1.0))
    e = np.asarray(energy) / E0 - 1.0
    assert m.substeps == 10_000                         # |ω|Δt ≤ 0.05: no sub-cycling
    assert np.sum(np.diff(np.sign(spin_y)) != 0) >= 4   # it flips about the intermediate axis
    assert L_err < 1e-13
    assert np.abs(e).max() < 2e-6
    assert abs(e[-1000:].mean() - e[:1000].mean()) < 1e-7
    assert orth < 1e-12
    row = m.observables()
    assert {"omega_x", "omega_y", "omega_z", "moment_x", "moment_z", "angular_momentum_y", "angle"} <= set(row)
    assert [row[f"angular_momentum_{a}"] for a in "xyz"] == L0.tolist()


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_free_3d_spin_about_a_principal_axis(axis):
    """Spun exactly about a principal axis (moments 1, 2, 3 kg m², ω = 2 rad/s), the body keeps
    spinning about it at the same rate, to the last bit, over 4000 steps of 0.01 s; the angle
    turned is ω t (mod 2π). Perturbed by 1e-3 rad/s in the two other components, the spin about
    the axis of smallest or largest moment stays (the perturbation stays within 3e-3 rad/s,
    measured 2.0e-3 and 1.4e-3) and about the intermediate axis it does not (it tumbles: the
    other components reach O(1))."""
    from mlsgalerkin.structure.steppers import FreeRigidMotion

    w0 = np.zeros(3)
    w0[axis] = 2.0
    m = FreeRigidMotion(_free_box((1.0, 2.0, 3.0), w0))
    m.start()
    for _ in range(4000):
        m.advance(0.01)
    assert np.array_equal(m.body_angular_velocity(), w0)
    assert np.allclose(m.omega, w0, rtol=0.0, atol=1e-13)
    turned = (2.0 * 40.0) % (2 * np.pi)
    assert m.angle() == pytest.approx(min(turned, 2 * np.pi - turned), abs=1e-9)
    perturbed = np.full(3, 1e-3)
    perturbed[axis] = 2.0
    p = FreeRigidMotion(_free_box((1.0, 2.0, 3.0), perturbed))
    p.start()
    off = 0.0
    for _ in range(4000):
        p.advance(0.01)
        off = max(off, np.abs(np.delete(p.body_angular_velocity(), axis)).max())
    if axis == 1:
        assert off > 1.0
    else:
        assert off < 3e-3


def test_free_3d_rotation_against_eulers_equations():
    """The body-frame ω of a torque-free body (moments 1, 2, 3 kg m², ω0 = (0.2, 1, 0.3) rad/s)
    against Euler's equations ``I Ω' = (I Ω) × Ω`` integrated by ``solve_ivp`` (rtol 1e-10) over
    2 s. The splitting is second order: at Δt = 0.01 s the largest error is 3.2e-6 rad/s
    (asserted below 1e-5, ``≈ 0.03 Δt²`` per unit time), and halving the step divides it by 4.0
    (asserted 3.6 to 4.4). The same body given by a turned, full inertia tensor ``Q I Qᵀ`` (the
    principal axes found by ``eigh``) follows ``Q Ω`` within the same bound."""
    from scipy.integrate import solve_ivp
    from scipy.spatial.transform import Rotation

    from mlsgalerkin.structure.steppers import FreeRigidMotion

    J, w0, T = np.array([1.0, 2.0, 3.0]), np.array([0.2, 1.0, 0.3]), 2.0
    ref = solve_ivp(lambda t, w: np.cross(J * w, w) / J, (0.0, T), w0, rtol=1e-10, atol=1e-12, dense_output=True)

    def error(dt, inertia=J, turn=None):
        turn = np.eye(3) if turn is None else turn
        m = FreeRigidMotion(_free_box(inertia, turn @ w0))
        m.start()
        worst = 0.0
        for k in range(round(T / dt)):
            m.advance(dt)
            worst = max(worst, np.abs(turn.T @ m.body_angular_velocity() - ref.sol((k + 1) * dt)).max())
        return worst

    coarse, fine = error(0.01), error(0.005)
    assert coarse < 1e-5
    assert 3.6 < coarse / fine < 4.4
    Q = Rotation.from_rotvec([0.3, -0.5, 0.8]).as_matrix()
    assert error(0.01, Q @ np.diag(J) @ Q.T, Q) < 1e-5


def test_free_3d_body_falls_with_its_spin_unchanged():
    """A free box spinning with ω0 = (0.3, -0.5, 2) rad/s falls under g = 9.81 m/s² from rest for
    0.2 s in the run loop (200 steps of 1 ms): the centre falls g t²/2 and moves at g t (exact
    for velocity Verlet under a constant force: 1e-12), the rotation is bit for bit that of the
    same body without gravity, kinetic energy plus the weight's potential is conserved within
    2e-8 relative (measured 5.0e-9: the rotational energy's O((|ω|Δt)²) oscillation; the fall
    itself is exact), and the surface's velocities and accelerations are ``V + ω × r`` and
    ``A + α × r + ω × (ω × r)``."""
    from mlsgalerkin.structure.steppers import FreeRigidMotion

    w0, g, t = (0.3, -0.5, 2.0), 9.81, 0.2
    body = _free_box((0.1, 0.15, 0.2), w0, name="box", gravity=(0.0, 0.0, -g))
    res = Simulation(Scene([body], [StructureScheme(dt_max=1e-3)], t_end=t)).run(progress=False)
    m = res.state.systems["structure"].body("box")
    assert res.state.t == pytest.approx(t, rel=1e-12)
    assert m.V == pytest.approx([0.0, 0.0, -g * t], abs=1e-12)
    assert m.c == pytest.approx([0.0, 0.0, -0.5 * g * t**2], abs=1e-12)
    ts = res.timeseries
    spin = FreeRigidMotion(_free_box((0.1, 0.15, 0.2), w0))
    spin.start()
    now = 0.0
    while now < t * (1 - 1e-12):         # the loop's steps: dt_max, the last one ending on t_end
        dt = min(1e-3, t - now)
        spin.advance(dt)
        now += dt
    assert spin.outer_steps == m.outer_steps
    assert np.array_equal(m.q, spin.q) and np.array_equal(m.L, spin.L) and np.array_equal(m.omega, spin.omega)
    e = np.asarray(ts["box_kinetic_energy"]) + np.asarray(ts["box_weight_potential"])
    assert np.ptp(e) < 2e-8 * e[0]
    assert ts["box_z"][-1] == pytest.approx(-0.5 * g * t**2, rel=1e-12)
    assert {"box_omega_x", "box_omega_y", "box_omega_z", "box_angle"} <= set(ts)
    s = m.surface()
    r = s.positions - m.c
    np.testing.assert_allclose(s.velocities, m.V + np.cross(m.omega, r), atol=1e-14)
    np.testing.assert_allclose(s.accelerations, m.A + np.cross(m.alpha, r) + np.cross(m.omega, np.cross(m.omega, r)),
                               atol=1e-13)


def test_free_3d_constant_torque_about_a_principal_axis():
    """A world torque of 0.6 N m about z (the principal axis of 3 kg m²) from a force couple on
    the surface nodes, through the load path of the fluid and contact forces (clear, add at the
    step's end, advance): from a spin of 0.5 rad/s about z, ω_z grows as 0.5 + M t/I exactly
    (1e-12; the kicks are exact for a constant torque), the other components stay zero
    (1e-13), the angle turned is 0.5 t + M t²/(2I), the angular acceleration the surface sees
    is M/I, and the work of the couple equals the gain of kinetic energy (1e-12 relative).
    Measured: all at round-off (ω_z 3e-15 relative, angle 5e-15 rad, work 1.2e-14)."""
    from mlsgalerkin.structure.steppers import FreeRigidMotion

    M, I3, w0, dt, n = 0.6, 3.0, 0.5, 0.01, 200
    m = FreeRigidMotion(_free_box((1.0, 2.0, I3), (0.0, 0.0, w0)))
    m.add_forces(_couple(m, M))
    assert m.F == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    assert m.M == pytest.approx([0.0, 0.0, M], abs=1e-15)
    m.start()
    E0 = m.kinetic_energy()
    for _ in range(n):
        m.advance(dt)
        m.clear_forces()
        m.add_forces(_couple(m, M))
    t = n * dt
    assert m.omega[2] == pytest.approx(w0 + M * t / I3, rel=1e-12)
    assert np.abs(m.omega[:2]).max() < 1e-13
    assert m.alpha == pytest.approx([0.0, 0.0, M / I3], abs=1e-13)
    turned = (w0 * t + 0.5 * M * t**2 / I3) % (2 * np.pi)
    assert m.angle() == pytest.approx(min(turned, 2 * np.pi - turned), abs=1e-10)
    assert m.work == pytest.approx(m.kinetic_energy() - E0, rel=1e-12)
    assert m.observables()["moment_z"] == pytest.approx(M, rel=1e-12)


def _loaded_free_body_steps(m, steps, start=0):
    """Advance ``m`` (a free 3D body) ``steps`` steps of 0.02 s under gravity, a couple about z
    varying in time and a force on one node (a moment about all axes), as the run loop does:
    advance, then clear and add the step's surface forces."""
    for k in range(start, start + steps):
        m.advance(0.02)
        m.clear_forces()
        f = _couple(m, 0.3 * np.sin(0.05 * k))
        f[0] += (0.4, -0.2, 0.1 * np.cos(0.1 * k))
        m.add_forces(f)


def test_free_3d_checkpoint_continues_bit_for_bit(tmp_path):
    """``checkpoint`` after 17 loaded steps, ``restore`` into a new motion, 23 more steps: the
    same bits as 40 steps in one go (orientation, angular momentum, ω, α, the centre, the work,
    every observable); and a run of the whole loop restarted from its checkpoint likewise."""
    from mlsgalerkin.structure.steppers import FreeRigidMotion

    def fresh():
        m = FreeRigidMotion(_free_box(np.array([[0.2, 0.01, 0.0], [0.01, 0.3, -0.02], [0.0, -0.02, 0.4]]),
                                  (1.0, -2.0, 3.0), gravity=(0.0, 0.0, -9.81), velocity=(0.1, 0.0, 0.0)))
        m.start()
        return m

    straight = fresh()
    _loaded_free_body_steps(straight, 40)
    first = fresh()
    _loaded_free_body_steps(first, 17)
    saved = first.checkpoint()
    second = FreeRigidMotion(first.body)
    second.restore(saved)
    _loaded_free_body_steps(second, 23, start=17)
    assert straight.substeps > straight.outer_steps   # |ω|Δt ≈ 0.075 > 0.05: it sub-cycles
    for name in ("q", "L", "omega", "alpha", "c", "V", "A", "F", "M"):
        assert np.array_equal(getattr(straight, name), getattr(second, name)), name
    assert straight.observables() == second.observables()

    def scene():
        return Scene([_free_box((0.1, 0.15, 0.2), (0.3, -0.5, 2.0), name="box", gravity=(0.0, 0.0, -9.81))], [StructureScheme(dt_max=1e-3)], t_end=0.05)

    whole = Simulation(scene()).run(progress=False)
    Simulation(scene()).run(out=tmp_path, progress=False, max_steps=17)
    resumed = Simulation(scene()).run(out=tmp_path, progress=False, restart="latest")
    a, b = (r.state.systems["structure"].body("box") for r in (whole, resumed))
    assert a.observables() == b.observables() and np.array_equal(a.q, b.q)


def test_bad_free_3d_rigid_input_is_refused_clearly():
    from mlsgalerkin.structure import Hinge, RigidBody

    with pytest.raises(ValueError, match="must be symmetric"):
        _free_box([[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 0.0)
    with pytest.raises(ValueError, match="must be positive definite"):
        _free_box([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]], 0.0)
    with pytest.raises(ValueError, match="principal moments of inertia must be finite and positive"):
        _free_box((1.0, -1.0, 1.0), 0.0)
    with pytest.raises(ValueError, match="triangle inequality"):
        _free_box((1.0, 1.0, 3.0), 0.0)
    with pytest.raises(ValueError, match="got shape"):
        _free_box(np.eye(2), 0.0)
    with pytest.raises(ValueError, match="angular_velocity as a finite \\(3,\\) vector"):
        _free_box(1.0, 2.0)
    square = _box((0, 0, 0), (1, 1, 1))
    with pytest.raises(ValueError, match="angular_velocity must be a finite scalar"):
        RigidBody("b", square, 1.0, 1.0, (0.5, 0.5, 0.5), constraint=Hinge((0.5, 0.5, 0.0), axis=(1.0, 0.0, 0.0)),
                  angular_velocity=(1.0, 0.0, 0.0))
    from mlsgalerkin.contact import ContactSurface

    flat = ContactSurface.polyline([(0, 0), (1, 0), (1, 1), (0, 1), (0, 0)])
    with pytest.raises(ValueError, match="in 2D inertia is a positive scalar"):
        RigidBody("r", flat, 1.0, (1.0, 1.0, 1.0), (0.5, 0.5))
    # accepted: a scalar, a diagonal, a full tensor; a 3D hinge uses eᵀ I e about its axis
    assert np.array_equal(_free_box(2.0, 0.0).inertia_tensor(), 2.0 * np.eye(3))
    assert np.array_equal(_free_box((1.0, 2.0, 3.0), 0.0).inertia, np.diag([1.0, 2.0, 3.0]))
    hinged = RigidBody("h", square, 1.0, (1.0, 2.0, 3.0), (0.5, 0.5, 0.5),
                       constraint=Hinge((0.5, 0.5, 0.0), axis=(0.0, 1.0, 0.0)))
    assert hinged.hinge_inertia() == pytest.approx(2.0 + 0.25)


# ---------------------------------------------------------------------- wall particles riding on a 3D surface
def _rotation(axis, angle):
    """Rodrigues' rotation matrix about the unit ``axis``."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


def test_3d_footprints_split_each_triangle_into_equal_pieces():
    """The footprints of a closed box of three face sizes, turned in space: each triangle of area
    ``A`` split into ``m²`` pieces, ``m = round(√A/spacing)`` (here 4, 3 and 2), of area ``A/m²``;
    the areas add to the surface's, each row of the average map sums to one and lies on its
    triangle's nodes, and the pieces integrate a linear field exactly (the centroid rule); on a
    triangle split in four the points are the centroids of the midpoint subdivision."""
    from mlsgalerkin.contact import ContactSurface
    from mlsgalerkin.contact.surface import TrianglePoints, surface_points

    box = _box((0.0, 0.0, 0.0), (0.3, 0.2, 0.1))
    surf = ContactSurface(box.nodes @ _rotation((1.0, 2.0, 0.5), 0.7).T + 0.3, box.facets)
    spacing = 0.04
    pts = surface_points(surf, spacing)
    assert isinstance(pts, TrianglePoints)
    A = surf.measures()
    m = np.maximum(1, np.round(np.sqrt(A) / spacing)).astype(int)
    assert sorted(set(m.tolist())) == [2, 3, 4]
    np.testing.assert_array_equal(np.bincount(pts.triangle, minlength=surf.n_facets), m**2)
    np.testing.assert_allclose(pts.area, (A / m**2)[pts.triangle], rtol=1e-12)
    assert pts.area.sum() == pytest.approx(A.sum(), rel=1e-12)
    W = pts.average.toarray()
    np.testing.assert_allclose(W.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(W >= 0.0)
    on_own = np.zeros_like(W, dtype=bool)
    on_own[np.arange(W.shape[0])[:, None], surf.facets[pts.triangle]] = True
    assert np.all(W[~on_own] == 0.0)
    field = lambda x: x @ np.array([2.0, -3.0, 0.7]) + 0.5
    x_p = W @ surf.nodes
    np.testing.assert_allclose(W @ field(surf.nodes), field(x_p), atol=1e-12)
    assert np.sum(pts.area * field(x_p)) == pytest.approx(np.sum(A * field(surf.centroids())), rel=1e-12)
    # m = 2: the four centroids of the triangles cut at the edge midpoints
    a, b, c = np.array([0.0, 0.0, 0.0]), np.array([0.2, 0.0, 0.05]), np.array([0.03, 0.15, 0.0])
    one = ContactSurface(np.array([a, b, c]), np.array([[0, 1, 2]]))
    q = surface_points(one, np.sqrt(one.measures()[0]) / 2)
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    expected = np.array([np.mean(t, axis=0) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    got = q.average @ one.nodes
    assert got.shape == (4, 3)
    assert np.abs(got[:, None, :] - expected[None, :, :]).sum(axis=2).min(axis=1).max() < 1e-12
    np.testing.assert_allclose(q.area, one.measures()[0] / 4, rtol=1e-12)


def test_3d_riding_particles_follow_a_rigid_motion_exactly():
    """A closed surface turned and moved rigidly, ``v = V + ω × (x − c)``: the footprints move
    with it, their normals turn with it at the rate ``ω × n``, and the wall particles riding on
    it (three layers behind) move with the same rigid motion."""
    from mlsgalerkin.dynamics import Surface
    from mlsgalerkin.fluid import WallBody
    from mlsgalerkin.interactions import riding_kinematics

    box = _box((0.0, 0.0, 0.0), (0.3, 0.2, 0.1))
    walls = WallBody.on_surface("w", box, 0.04, follows="body", layers=3)
    pts = walls.footprints
    x0, v0, n0, dn0 = pts.kinematics(box.nodes, np.zeros_like(box.nodes))
    assert np.all(v0 == 0) and np.all(dn0 == 0)
    np.testing.assert_allclose(n0, box.normals()[pts.triangle], atol=1e-12)
    R, shift = _rotation((0.3, -1.0, 2.0), 1.1), np.array([0.5, -0.2, 0.1])
    omega, V, c = np.array([1.5, -0.4, 2.0]), np.array([0.3, 0.1, -0.7]), shift + np.array([0.1, 0.05, 0.0])
    x = box.nodes @ R.T + shift
    v = V + np.cross(omega, x - c)
    xp, vp, n, dn = pts.kinematics(x, v)
    np.testing.assert_allclose(xp, x0 @ R.T + shift, atol=1e-12)
    np.testing.assert_allclose(vp, V + np.cross(omega, xp - c), atol=1e-12)
    np.testing.assert_allclose(n, n0 @ R.T, atol=1e-12)
    np.testing.assert_allclose(dn, np.cross(omega, n), atol=1e-12)
    pos, vel, acc, nw = riding_kinematics(Surface("body", x, v, box.facets), pts, walls.anchors)
    np.testing.assert_allclose(pos, walls.positions @ R.T + shift, atol=1e-12)
    np.testing.assert_allclose(vel, V + np.cross(omega, pos - c), atol=1e-12)
    np.testing.assert_allclose(nw, walls.normals @ R.T, atol=1e-12)
    assert np.all(acc == 0)


@pytest.mark.parametrize("ny, exact", [(10, True), (5, False)])
def test_3d_wall_particles_on_the_top_of_a_plate(ny, exact):
    """``WallBody.on_surface`` on the wet top face of a Hex1 plate (0.2 × 0.1 m, 0.04 m thick,
    spacing 0.01 m, 3 layers): every particle inside the plate, ``(l + ½)·spacing`` below its
    top, with the face's normal. Elements of 0.02 × 0.01 m give triangles of ``√A = spacing``:
    exactly ``area/spacing²`` particles a layer. Square elements of 0.02 m (``√A = √2·spacing``,
    ``m = 1``) give one particle per ``2 spacing²``: the bound checked is each triangle's
    ``m²·spacing²`` within ``[(√A − spacing/2)², (√A + spacing/2)²]``."""
    from mlsgalerkin.fluid import WallBody

    dx, Lx, Ly, h = 0.01, 0.2, 0.1, 0.04
    mesh = MeshHex.init_tensor(np.linspace(0, Lx, 11), np.linspace(0, Ly, ny + 1), np.linspace(-h, 0.0, 3))
    plate = ElasticBody("plate", mesh, ElasticMaterial(1e9, 0.3, 1000.0), "Hex1",
                        wet=lambda x: np.isclose(x[2], 0.0))
    top = plate.wet.contact_surface()
    w = WallBody.on_surface("plate_walls", top, dx, follows="plate", layers=3)
    per_layer = w.n // 3
    assert w.n == 3 * per_layer and w.dim == 3 and w.follows == "plate"
    if exact:
        assert per_layer == round(Lx * Ly / dx**2) == 200
    A = top.measures()
    m = np.bincount(w.footprints.triangle, minlength=top.n_facets) ** 0.5
    assert np.all(m * dx >= np.sqrt(A) - dx / 2 - 1e-12) and np.all(m * dx <= np.sqrt(A) + dx / 2 + 1e-12)
    assert per_layer == int(np.sum(m**2))
    np.testing.assert_allclose(w.normals, np.tile([0.0, 0.0, 1.0], (w.n, 1)), atol=1e-12)
    layer = np.repeat(np.arange(3), per_layer)
    np.testing.assert_allclose(w.positions[:, 2], -(layer + 0.5) * dx, atol=1e-12)
    np.testing.assert_allclose(w.anchors[:, 2], (layer + 0.5) * dx, atol=1e-12)
    assert np.all((w.positions[:, :2] > 0.0) & (w.positions[:, :2] < [Lx, Ly]))
    assert np.all(w.positions[:, 2] > -h)


def _water_on_a_3d_plate(t_end: float, ny: int = 10, nx: int = 5):
    """A 0.2 × 0.2 m water column 0.1 m deep (dx 0.02 m: 500 particles, at hydrostatic rest) on a
    clamped Hex1 plate 0.02 m thick (E = 1 GPa, ρ = 2700 kg/m³, Newmark), in a box of three layers
    of fixed wall particles; wall particles riding on the plate's wet top face (elements of
    0.04 × 0.02 m: one per 0.02² m² of face) and ``StructureCoupling`` with the wall acceleration,
    as ``hydrostatic_plate``."""
    from mlsgalerkin.fluid import (
        DensityFilter,
        Gravity,
        StructureCoupling,
        TaitPressure,
        WallBody,
        Walls,
        hydrostatic_density,
        lattice,
    )
    from mlsgalerkin.scene import Approximation, Probe

    dx, L, H, g, rho, layers = 0.02, 0.2, 0.1, 9.81, 1000.0, 3
    c0 = 10.0 * np.sqrt(2.0 * g * H)
    water = FluidBody.block("water", (0.0, 0.0, 0.0), (L, L, H), dx, [Phase("water", rho)])
    water.density[:] = hydrostatic_density(np.full(water.n, rho), H - water.positions[:, 2], g, c0)
    mesh = MeshHex.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, L, ny + 1), np.linspace(-0.02, 0.0, 2))
    edge = lambda x: np.isclose(x[0], 0) | np.isclose(x[0], L) | np.isclose(x[1], 0) | np.isclose(x[1], L)
    plate = ElasticBody("plate", mesh, ElasticMaterial(1e9, 0.3, 2700.0), "Hex1", clamped=edge,
                        wet=lambda x: np.isclose(x[2], 0.0), integrator="newmark",
                        points={"mid": (L / 2, L / 2, -0.01)})
    riding = WallBody.on_surface("plate_walls", plate.wet.contact_surface(), dx, follows="plate", reference_density=rho)
    top = 1.5 * H
    box = lattice((-layers * dx,) * 3, (L + layers * dx, L + layers * dx, top), dx)
    sides = box[~((box[:, 0] > 0) & (box[:, 0] < L) & (box[:, 1] > 0) & (box[:, 1] < L))]
    nrm = np.clip(sides, 0.0, [L, L, top]) - sides
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    walls = WallBody("sides", sides, dx, normals=nrm, reference_density=rho)
    coupling = StructureCoupling("water", "plate", walls="plate_walls", thickness=0.25 * dx, wall_acceleration=1.0)
    n = water.n
    scene = Scene([water, walls, riding, plate], [FluidScheme([TaitPressure(c0), Gravity((0.0, 0.0, -g)), Walls("free_slip"), MonaghanViscosity(0.2),
                   DensityFilter(20)], approximation=Approximation(h_factor=1.3), stabilisation="as_listed")], t_end=t_end, interactions=[coupling], probes=[Probe("lowest_water", lambda state: float(state.fluid.x[:n, 2].min()))])
    return scene, plate, water.n * rho * dx**3 * g, rho * g * H


def test_3d_plate_under_water_carries_its_weight_through_riding_wall_particles():
    """The water column at rest on the clamped plate for 0.2 s (about 300 steps, 5 s): the load the
    plate receives (wall-particle reactions spread to its nodes by the transpose of the footprint
    map, plus contact) oscillates by about ±4 % with the column's pressure waves (period
    ``4H/c0 ≈ 0.03`` s); its mean over the second half balances the water's weight within 1 %
    (measured 0.3 %, the same 1 % as the 2D plate; the mean over three periods leaves well under
    1 % of the oscillation), the horizontal load is below 0.5 % of it (measured 0.15 %: the
    triangles' one-sided diagonals make the riding particles' pattern not quite symmetric), no
    water particle goes below the plate's top, and the mean mid-span deflection is within 3 %
    of the plate model's own static answer under the uniform load ρgH (measured 0.4 %)."""
    scene, plate, weight, pressure = _water_on_a_3d_plate(0.2)
    assert scene.interactions[0].problems(scene) == []
    res = Simulation(scene).run(progress=False)
    assert res.summary["status"] == "completed"
    ts = res.timeseries
    t = np.asarray(ts["time"])
    late = t >= 0.5 * t[-1]
    load = np.stack([np.asarray(ts[f"plate_force_{a}"]) for a in "xyz"], axis=1)
    assert abs(-load[late, 2].mean() / weight - 1.0) < 0.01
    assert np.all(np.abs(load[late, :2].mean(axis=0)) < 5e-3 * weight)
    summary = res.summary["interactions"]["coupling"]
    reported = np.array(summary["last_wall_reaction_N"]) + np.array(summary["last_contact_force_N"])
    assert reported.shape == (3,)
    np.testing.assert_allclose(reported, load[-1], rtol=1e-6, atol=1e-9 * weight)
    assert min(ts["lowest_water"]) > 0.0
    static = plate.static(plate.edge_traction(lambda x: np.isclose(x[2], 0.0), (0.0, 0.0, -pressure)))
    w_static = plate.point_displacements(static)["mid"][2]
    assert np.mean(np.asarray(ts["plate_mid_uz"])[late]) / w_static == pytest.approx(1.0, abs=0.03)


@pytest.mark.parametrize("nx, ny, measured", [(5, 5, -0.0232), (10, 10, 0.0329)])
def test_3d_uneven_footprints_still_carry_the_weight(nx, ny, measured):
    """Square faces cut in two give triangles whose pieces cannot cover ``spacing²`` each: 0.04 m
    faces give one particle per ``2 dx²``, 0.02 m faces one per ``dx²/2``. Each riding particle
    then integrates its own footprint times ``dx`` (``WallBody.volumes``); without that the load
    was 5.2 % low and 4.5 % high. Measured with it: −2.3 % and +3.3 % (the remaining error is the
    uneven particle pattern against the fluid's lattice); asserted within 4 %, and within 0.5 % of
    the measured value, so that a change of the footprints or volumes shows."""
    scene, plate, weight, pressure = _water_on_a_3d_plate(0.2, ny=ny, nx=nx)
    res = Simulation(scene).run(progress=False)
    assert res.summary["status"] == "completed"
    ts = res.timeseries
    t = np.asarray(ts["time"])
    late = t >= 0.5 * t[-1]
    error = -np.asarray(ts["plate_force_z"])[late].mean() / weight - 1.0
    assert abs(error) < 0.04
    assert abs(error - measured) < 0.005
    assert min(ts["lowest_water"]) > 0.0
