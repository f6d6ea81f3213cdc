"""Node-to-surface penalty contact (:mod:`mlsgalerkin.contact`): a particle resting on a segment
or a triangle, separation, momentum of slave plus master, the energy of a bounce, the stable
step, inside and outside corners, every numba kernel against its numpy reference on random 2D
and 3D geometry (hypothesis), the broad phase against brute force, the two-body interaction, and
clear errors for bad input.

Numbers quoted in comments were measured with the defaults (α = 0.1, ζ = 0.03, C = 0.5).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.contact import (
    DEFAULT_ALPHA,
    DEFAULT_DAMPING,
    STABILITY_FACTOR,
    ContactSurface,
    PenaltyLaw,
    candidate_pairs,
    candidate_pairs_reference,
    closest_points,
    closest_points_reference,
    facet_normals,
    facet_normals_reference,
    penalty_forces,
    penalty_forces_reference,
    penalty_stiffness,
    rigid_time_step,
    search_margin,
)
from mlsgalerkin.contact.geometry import EDGE, INTERIOR, VERTEX
from mlsgalerkin.dynamics import Solver, Surface
from mlsgalerkin.interactions import PenaltyContact

G = 9.81
DT = 1e-4       # reference time step (s)
G0 = 0.005      # contact thickness (m)
REACH = 0.01    # reach (m)


def floor(dim: int, half: float = 1.0) -> ContactSurface:
    """A horizontal floor at height 0 with its normal up: one segment (2D), two triangles (3D)."""
    if dim == 2:
        return ContactSurface.polyline([(half, 0.0), (-half, 0.0)])
    nodes = [(-half, -half, 0.0), (half, -half, 0.0), (half, half, 0.0), (-half, half, 0.0)]
    return ContactSurface(np.array(nodes), np.array([[0, 1, 2], [0, 2, 3]]))


def up(dim: int) -> np.ndarray:
    e = np.zeros(dim)
    e[-1] = 1.0
    return e


def forces(x, v, m, surf, master_x=None, master_v=None, master_m=None, **kw):
    kw.setdefault("dt_ref", DT)
    kw.setdefault("thickness", G0)
    kw.setdefault("reach", REACH)
    return penalty_forces(np.atleast_2d(x), np.atleast_2d(v), m, surf.nodes if master_x is None else master_x,
                          master_v, master_m, surf.facets, **kw)


# ------------------------------------------------------------------ surfaces
def test_surface_orientation_and_tank_normals_point_inward():
    assert floor(2).normals().tolist() == [[0.0, 1.0]]
    np.testing.assert_allclose(floor(3).normals(), [[0, 0, 1], [0, 0, 1]], atol=1e-15)
    for lo, hi in (((0.0, 0.0), (1.0, 0.5)), ((0.0, 0.0, 0.0), (1.0, 0.5, 0.3))):
        lo, hi = np.array(lo), np.array(hi)
        for open_top in (True, False):
            tank = ContactSurface.tank(lo, hi, open_top=open_top)
            faces = (3 if open_top else 4) if lo.size == 2 else 2 * (5 if open_top else 6)
            assert tank.n_facets == faces
            inside = tank.centroids() + 1e-3 * tank.normals()
            assert np.all((inside > lo) & (inside < hi)), "a tank normal points out of the box"
    square = ContactSurface.polyline([(0, 0), (1, 0), (1, 1), (0, 1)], closed=True)  # counter-clockwise
    assert np.all(np.einsum("ij,ij->i", square.centroids() - 0.5, square.normals()) > 0)  # outward
    assert np.all(np.einsum("ij,ij->i", square.flipped().centroids() - 0.5, square.flipped().normals()) < 0)
    np.testing.assert_array_equal(square.flipped().oriented((0.5, 0.5)).normals(), square.normals())
    np.testing.assert_allclose(square.measures(), 1.0)
    assert repr(ContactSurface.tank((0, 0, 0), (1, 1, 1))) == "ContactSurface(3D, 8 nodes, 10 triangles)"


@pytest.mark.parametrize("nodes, facets, fragment", [
    (np.zeros((3, 4)), [[0, 1]], "(m, 2) or (m, 3)"),
    ([[0.0, 0.0]], [[0, 0]], "needs 2 nodes"),
    ([[0.0, 0.0], [np.nan, 1.0]], [[0, 1]], "node 1 has a NaN"),
    ([[0.0, 0.0], [1.0, 0.0]], [[0, 1, 1]], "facets of shape (k, 2)"),
    ([[0.0, 0.0], [1.0, 0.0]], np.zeros((0, 2), dtype=int), "with k >= 1"),
    ([[0.0, 0.0], [1.0, 0.0]], [[0, 2]], "must lie in [0, 2)"),
    ([[0.0, 0.0], [1.0, 0.0]], [[0.5, 1]], "integer node indices"),
    ([[0.0, 0.0], [1.0, 0.0]], [[1, 1]], "repeats a node"),
    ([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]], [[1, 2]], "zero length"),
    ([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]], [[0, 1, 2]], "zero area"),
])
def test_bad_surfaces_are_refused_with_the_reason(nodes, facets, fragment):
    with pytest.raises(ValueError) as info:
        ContactSurface(np.asarray(nodes, dtype=float), np.asarray(facets))
    assert fragment in str(info.value)


# ------------------------------------------------------------------ one particle on a floor
def settle(surf, x0, m, steps, dt=DT, g=G, **kw):
    """KDK of a single particle under gravity on ``surf``; returns positions, gaps, forces."""
    d = surf.dim
    x, v = np.array(x0, dtype=float)[None], np.zeros((1, d))
    grav = -g * up(d)
    res = forces(x, v, m, surf, **kw)
    xs, gaps, fs = [], [], []
    for _ in range(steps):
        v += 0.5 * dt * (res.slave_forces / m + grav)
        x += dt * v
        res = forces(x, v, m, surf, **kw)
        v += 0.5 * dt * (res.slave_forces / m + grav)
        xs.append(x[0].copy())
        gaps.append(res.gaps[0])
        fs.append(res.slave_forces[0].copy())
    return np.array(xs), np.array(gaps), np.array(fs)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_particle_resting_on_a_facet_balances_gravity(dim, one_numba_thread):
    """Dropped onto the contact thickness from rest, the particle rings at ω = √(k/m) = √α/Δt and
    settles (3 % of critical damping) where the penalty force carries its weight:
    ``g = −m g_acc / k = −g_acc Δt²/α``."""
    m = 0.1
    surf = floor(dim)
    x0 = np.full(dim, 0.2)
    x0[-1] = G0  # touching: g = 0
    xs, gaps, fs = settle(surf, x0, m, steps=1500)
    k = penalty_stiffness(DEFAULT_ALPHA, m, DT)
    assert k == pytest.approx(DEFAULT_ALPHA * m / DT**2)
    assert gaps[-1] == pytest.approx(-m * G / k, rel=1e-4)            # −9.81e-7 m
    np.testing.assert_allclose(fs[-1], m * G * up(dim), rtol=1e-4, atol=1e-12)
    np.testing.assert_allclose(xs[:, :-1], 0.2, atol=1e-15)             # no sideways force on a floor
    # the ringing has the frequency the stiffness was chosen for: ω Δt_ref = √α
    crossings = np.flatnonzero(np.diff(np.sign(gaps[:400] + m * G / k)) != 0)
    period = 2.0 * np.mean(np.diff(crossings)) * DT
    damped = math.sqrt(DEFAULT_ALPHA) / DT * math.sqrt(1 - 0.03**2)
    assert period == pytest.approx(2 * math.pi / damped, rel=0.02)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("where", ["above the thickness", "exactly touching", "behind beyond the reach",
                                   "past the open end, behind", "far away"])
def test_no_force_when_separated(dim, where):
    x = np.full(dim, 0.3)
    x[-1] = {"above the thickness": G0 * 1.001, "exactly touching": G0, "behind beyond the reach": G0 - REACH * 1.001,
             "past the open end, behind": -0.001, "far away": 5.0}[where]
    if where == "past the open end, behind":
        x[0] = 1.002  # beyond the floor's end, below its plane: the far side of a thin plate
    res = forces(x, np.zeros(dim), 0.2, floor(dim))
    assert res.contacts == 0 and res.active_slaves == 0 and res.max_penetration == 0.0
    assert np.all(res.slave_forces == 0) and np.all(res.master_forces == 0) and np.all(res.total_force == 0)
    assert res.stable_dt == math.inf and res.pair_facet.size == 0 and res.pair_weights.shape == (0, dim)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_force_is_never_attractive(dim):
    """Inside the thickness but leaving fast: −k g − c ġ < 0 is clamped to no force."""
    x = np.full(dim, 0.3)
    x[-1] = G0 - 1e-5
    leaving = 10.0 * up(dim)
    res = forces(x, leaving, 0.2, floor(dim))
    assert res.contacts == 1 and res.pair_force[0] == 0.0 and np.all(res.slave_forces == 0)
    approaching = forces(x, -leaving, 0.2, floor(dim))
    k, c = penalty_stiffness(DEFAULT_ALPHA, 0.2, DT), 2 * 0.03 * math.sqrt(DEFAULT_ALPHA) * 0.2 / DT
    assert approaching.pair_force[0] == pytest.approx(k * 1e-5 + c * 10.0)
    np.testing.assert_allclose(approaching.slave_forces[0], approaching.pair_force[0] * up(dim), atol=1e-9)


@pytest.mark.parametrize("dim", [2, 3])
def test_stored_energy_is_the_potential_of_the_spring(dim):
    """One slave ``δ`` inside the thickness of a rigid floor stores ``½ k δ²``, ``k = α m/Δt²``;
    and the spring force is minus its derivative: ``(E(δ + ε) − E(δ − ε))/2ε = k δ`` at rest."""
    def pressed(depth):
        x = np.full(dim, 0.3)
        x[-1] = G0 - depth
        return forces(x, np.zeros(dim), 0.2, floor(dim))

    k = penalty_stiffness(DEFAULT_ALPHA, 0.2, DT)
    res = pressed(2e-4)
    assert res.pair_stiffness.tolist() == pytest.approx([float(k)], rel=1e-14)
    assert res.stored_energy == pytest.approx(0.5 * k * 2e-4 ** 2, rel=1e-9)
    eps = 1e-7
    slope = (pressed(2e-4 + eps).stored_energy - pressed(2e-4 - eps).stored_energy) / (2 * eps)
    assert slope == pytest.approx(res.pair_force[0], rel=1e-6)
    assert pressed(-1e-4).stored_energy == 0.0          # outside the thickness: no spring


# ------------------------------------------------------------------ corners
def test_inside_corner_of_a_2d_tank_holds_with_both_walls():
    tank = ContactSurface.tank((0.0, 0.0), (1.0, 1.0))
    res = forces([0.003, 0.004], [0.0, 0.0], 0.1, tank)
    k = penalty_stiffness(DEFAULT_ALPHA, 0.1, DT)
    assert res.contacts == 2 and res.active_slaves == 1
    np.testing.assert_allclose(res.slave_forces[0], [k * 0.002, k * 0.001], rtol=1e-12)
    np.testing.assert_allclose(res.total_force, -res.slave_forces[0])
    assert res.stable_dt == pytest.approx(rigid_time_step(DEFAULT_ALPHA, 0.03, DT, 2), rel=1e-12)


def test_inside_corner_of_a_3d_tank_holds_with_three_walls():
    tank = ContactSurface.tank((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    res = forces([0.001, 0.002, 0.003], [0.0, 0.0, 0.0], 0.1, tank)
    k = penalty_stiffness(DEFAULT_ALPHA, 0.1, DT)
    assert res.contacts == 3
    np.testing.assert_allclose(res.slave_forces[0], k * np.array([0.004, 0.003, 0.002]), rtol=1e-12)
    assert res.stable_dt == pytest.approx(rigid_time_step(DEFAULT_ALPHA, 0.03, DT, 3), rel=1e-12)


def test_outside_corner_is_rounded_and_counted_once():
    block = ContactSurface.polyline([(0, 0), (1, 0), (1, 1), (0, 1)], closed=True)  # normals outward
    s = 0.003 / math.sqrt(2)
    res = forces([1 + s, 1 + s], [0.0, 0.0], 0.1, block)
    assert res.contacts == 1
    np.testing.assert_allclose(res.pair_normal[0], [2**-0.5, 2**-0.5], rtol=1e-12)
    assert res.pair_facet[0] in (1, 2) and res.pair_gap[0] == res.gaps[0]
    assert res.gaps[0] == pytest.approx(0.003 - G0, rel=1e-12)
    # the corner node takes the whole reaction
    np.testing.assert_allclose(res.master_forces[2], -res.slave_forces[0], rtol=1e-12)
    # a gentle bend (10° < feature angle) acts as one smooth surface: one contact
    bend = ContactSurface.polyline([(1, -math.tan(math.radians(10))), (0, 0), (-1, -math.tan(math.radians(10)))])
    assert forces([0.0, 0.002], [0.0, 0.0], 0.1, bend).contacts == 1


# ------------------------------------------------------------------ equal and opposite
def _moment(x, f, centre):
    """Total moment about ``centre`` of forces ``f`` at ``x`` (a scalar in 2D, a vector in 3D)."""
    r = x - centre
    return float(np.sum(r[:, 0] * f[:, 1] - r[:, 1] * f[:, 0])) if x.shape[1] == 2 else np.cross(r, f).sum(axis=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_reactions_are_equal_opposite_and_give_the_reported_moment(dim, rng):
    surf = ContactSurface.tank(np.zeros(dim), np.ones(dim))
    x = rng.uniform(-0.002, 1.002, (400, dim))
    x[:, :1] = rng.uniform(-0.002, 0.004, (400, 1))  # crowd one wall
    centre = rng.uniform(-1, 1, dim)
    res = forces(x, rng.normal(0, 0.1, (400, dim)), rng.uniform(0.01, 0.1, 400), surf, centre=centre,
                 master_m=rng.uniform(0.5, 1.0, surf.n_nodes), master_v=rng.normal(0, 0.1, (surf.n_nodes, dim)))
    assert res.contacts > 200
    scale = np.abs(res.slave_forces).sum()
    np.testing.assert_allclose(res.slave_forces.sum(axis=0) + res.master_forces.sum(axis=0), 0, atol=1e-14 * scale)
    np.testing.assert_allclose(res.total_force, res.master_forces.sum(axis=0), atol=1e-14 * scale)
    # moment about the centre: of the reactions at the master nodes = of −f_s at the contact points,
    # and the slave forces have the opposite moment (x_s − x_c ∥ n: no torque in the pair)
    s, xc, fc = res.contact_points(surf.nodes, surf.facets)
    np.testing.assert_allclose(_moment(surf.nodes, res.master_forces, centre), res.moment, atol=1e-13 * scale)
    np.testing.assert_allclose(_moment(xc, -fc, centre), res.moment, atol=1e-13 * scale)
    np.testing.assert_allclose(_moment(x[s], fc, centre) + np.asarray(res.moment), 0, atol=1e-13 * scale)


@pytest.mark.parametrize("dim", [2, 3])
def test_momentum_of_slave_plus_master_is_conserved_to_round_off(dim, one_numba_thread):
    """A particle strikes a free facet (nodal masses, no other force), KDK at the contact's own
    stable step: linear and angular momentum of the pair stay to round-off through the impact."""
    if dim == 2:
        surf = ContactSurface.polyline([(0.1, 0.0), (-0.1, 0.0)])
        xs, vs = np.array([[0.03, 0.02]]), np.array([[0.3, -1.0]])
    else:
        surf = ContactSurface(np.array([[-0.1, -0.1, 0], [0.1, -0.1, 0], [0.0, 0.1, 0.0]]), np.array([[0, 1, 2]]))
        xs, vs = np.array([[0.02, -0.01, 0.02]]), np.array([[0.3, 0.1, -1.0]])
    ms = np.array([0.1])
    mm = np.array([0.3, 0.2, 0.25])[:surf.n_nodes]
    xm, vm = surf.nodes.copy(), np.zeros_like(surf.nodes)

    def momenta():
        p = ms @ vs + mm @ vm
        x, v, m = np.vstack([xs, xm]), np.vstack([vs, vm]), np.concatenate([ms, mm])
        ang = m @ (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]) if dim == 2 else (m[:, None] * np.cross(x, v)).sum(axis=0)
        return p, ang

    def evaluate():
        return penalty_forces(xs, vs, ms, xm, vm, mm, surf.facets, dt_ref=DT, thickness=G0, reach=REACH)

    p0, l0 = momenta()
    res = evaluate()
    dt = 0.9 * rigid_time_step(DEFAULT_ALPHA, 0.03, DT, 2 * dim)  # the bound PenaltyContact applies
    peak, worst_p, worst_l = 0.0, 0.0, 0.0
    for _ in range(400):
        assert dt <= res.stable_dt
        vs += 0.5 * dt * res.slave_forces / ms[:, None]
        vm += 0.5 * dt * res.master_forces / mm[:, None]
        xs += dt * vs
        xm += dt * vm
        res = evaluate()
        vs += 0.5 * dt * res.slave_forces / ms[:, None]
        vm += 0.5 * dt * res.master_forces / mm[:, None]
        p, ang = momenta()
        peak = max(peak, float(np.abs(res.slave_forces).max()))
        worst_p = max(worst_p, float(np.abs(p - p0).max()))
        worst_l = max(worst_l, float(np.abs(ang - l0).max()))
    assert peak > 100.0 and vs[0, -1] > 0  # it hit and bounced
    # |p0| ≈ 0.1 kg m/s; measured drifts 3e-17 and 9e-17 (2D), 1e-17 and 8e-17 (3D): round-off
    assert worst_p < 1e-15 and worst_l < 1e-15


# ------------------------------------------------------------------ energy of a bounce
def bounce(damping: float, bounces: int, dim: int = 2, dt: float = DT) -> np.ndarray:
    """A particle dropped from 15 mm above the contact thickness onto a rigid floor under gravity,
    KDK at the reference step; its energy ``½mv² + m g_acc (y − g0)`` before the first contact
    and after each of ``bounces`` contacts."""
    m = 0.05
    surf = floor(dim)
    x, v = np.zeros((1, dim)), np.zeros((1, dim))
    x[0, -1] = G0 + 0.015
    grav = -G * up(dim)

    def energy():
        return 0.5 * m * float(v[0] @ v[0]) + m * G * float(x[0, -1] - G0)

    res = forces(x, v, m, surf, damping=damping)
    out, touching = [energy()], False
    while len(out) <= bounces:
        v += 0.5 * dt * (res.slave_forces / m + grav)
        x += dt * v
        res = forces(x, v, m, surf, damping=damping)
        v += 0.5 * dt * (res.slave_forces / m + grav)
        if res.contacts:
            touching = True
        elif touching:
            touching = False
            out.append(energy())
    return np.array(out)


def test_a_bouncing_particle_gains_no_energy(one_numba_thread):
    """With the default damping every bounce loses energy: the ratio is close to the restitution
    of a clamped spring-dashpot, e² = 0.831 at ζ = 0.03 (solved exactly; 0.828 unclamped); at
    ω Δt = √α = 0.32 the explicit step gives 0.82–0.86 (mean 0.83 over 8 bounces)."""
    e = bounce(0.03, 8)
    ratios = e[1:] / e[:-1]
    assert np.all(ratios < 0.9) and np.all(ratios > 0.8), ratios
    e3 = bounce(0.03, 2, dim=3)
    np.testing.assert_allclose(e3, e[:3], rtol=1e-12)  # a triangle floor: the same bounce


def test_an_undamped_impact_returns_its_energy_on_average(one_numba_thread):
    """Undamped, an impact returns the energy it took to within the error of the explicit step,
    which depends on where in a step the contact begins: e² − 1 within ±0.9 % over 50 entry
    phases (ω Δt = 0.32), mean 3e-4. One per cent of critical damping already makes every
    impact lose energy; the default is 3 %."""
    def restitution2(zeta, phase):
        m, v_in = 0.05, 0.5
        x, v = np.array([[0.0, G0 + phase * v_in * DT]]), np.array([[0.0, -v_in]])
        res = forces(x, v, m, floor(2), damping=zeta)
        for _ in range(40):
            v += 0.5 * DT * res.slave_forces / m
            x += DT * v
            res = forces(x, v, m, floor(2), damping=zeta)
            v += 0.5 * DT * res.slave_forces / m
        assert res.contacts == 0 and v[0, 1] > 0
        return (v[0, 1] / v_in) ** 2

    phases = np.linspace(0.0, 1.0, 50, endpoint=False)
    undamped = np.array([restitution2(0.0, p) for p in phases])
    assert abs(undamped.mean() - 1) < 1e-3 and np.abs(undamped - 1).max() < 0.012
    assert max(restitution2(0.01, p) for p in phases[::5]) < 0.97


def test_the_stable_step_of_a_contact_spring():
    """A particle held by ``d`` contact springs of ``k = α m/Δt_ref²`` each, integrated by KDK:
    bounded below ``2(√(1+ζ²) − ζ)/ω``, growing above it; the limit the contact reports is C
    times that."""
    alpha, zeta, dt_ref, d = 0.1, 0.03, 1e-4, 2
    omega = math.sqrt(d * alpha) / dt_ref
    limit = 2 * (math.sqrt(1 + zeta**2) - zeta) / omega
    assert rigid_time_step(alpha, zeta, dt_ref, d) == pytest.approx(STABILITY_FACTOR * limit)

    def amplitude(dt):
        x, v = 1.0, 0.0
        a = -omega**2 * x - 2 * zeta * omega * v
        for _ in range(1000):
            v += 0.5 * dt * a
            x += dt * v
            a = -omega**2 * x - 2 * zeta * omega * v  # the kernel's damping uses the half-step velocity
            v += 0.5 * dt * a
        return abs(x) + abs(v) / omega

    assert amplitude(0.98 * limit) < 1.0 and amplitude(1.02 * limit) > 10.0


def test_stable_step_of_a_deformable_master_bounds_the_true_frequency(rng):
    """The Gershgorin bound of the kernel against the largest eigenfrequency of the contact
    springs' ``M⁻¹K`` (slaves and master nodes), on a random crowd touching a free polyline."""
    surf = ContactSurface.polyline(np.column_stack([np.linspace(1, 0, 6), rng.uniform(-0.01, 0.01, 6)]))
    n = 30
    x = np.column_stack([rng.uniform(0, 1, n), rng.uniform(-0.004, 0.004, n)])
    ms, mm = rng.uniform(0.01, 0.1, n), rng.uniform(0.01, 0.1, surf.n_nodes)
    res = forces(x, np.zeros((n, 2)), ms, surf, master_m=mm)
    assert res.contacts > 10
    K = np.zeros((n + surf.n_nodes, n + surf.n_nodes))
    for s, j, weights in zip(res.pair_slave, res.pair_facet, res.pair_weights):
        b = np.zeros(n + surf.n_nodes)
        b[s] = 1.0
        b[n + surf.facets[j]] = -weights
        w = weights @ mm[surf.facets[j]]
        k = DEFAULT_ALPHA * (ms[s] * w / (ms[s] + w)) / DT**2
        K += k * np.outer(b, b)
    minv = 1 / np.sqrt(np.concatenate([ms, mm]))
    omega = math.sqrt(np.linalg.eigvalsh(minv[:, None] * K * minv[None, :]).max())
    exact = STABILITY_FACTOR * 2 * (math.sqrt(1 + 0.03**2) - 0.03) / omega
    assert res.stable_dt <= exact * (1 + 1e-12)
    assert res.stable_dt > 0.25 * exact  # and not uselessly small (measured: 0.61–0.75 of it over 20 seeds)


# ------------------------------------------------------------------ random geometry (hypothesis)
def random_surface(rng: np.random.Generator, dim: int) -> ContactSurface:
    """A wobbly closed or open polygon (2D), a bumpy height field or a box (3D); either orientation."""
    kind = rng.integers(3)
    if dim == 2:
        if kind == 2:
            surf = ContactSurface.tank(rng.uniform(-1, 0, 2), rng.uniform(0.5, 1.5, 2), open_top=bool(rng.integers(2)))
        else:
            k = int(rng.integers(3, 14))
            ang = np.sort(rng.uniform(0, 2 * np.pi, k))
            r = 1 + 0.3 * rng.uniform(-1, 1, k)
            surf = ContactSurface.polyline(np.column_stack([r * np.cos(ang), r * np.sin(ang)]), closed=kind == 0)
    elif kind == 2:
        surf = ContactSurface.tank(rng.uniform(-1, 0, 3), rng.uniform(0.5, 1.5, 3), open_top=bool(rng.integers(2)))
    else:
        nx, ny = (int(v) for v in rng.integers(2, 6, 2))
        gx, gy = np.meshgrid(np.linspace(-1, 1, nx), np.linspace(-1, 1, ny), indexing="ij")
        z = (0.3 if kind else 0.02) * rng.normal(size=gx.shape)
        nodes = np.column_stack([gx.ravel(), gy.ravel(), z.ravel()])
        idx = np.arange(nx * ny).reshape(nx, ny)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        surf = ContactSurface(nodes, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])]))
    return surf.flipped() if rng.integers(2) else surf


def slaves_near(rng: np.random.Generator, surf: ContactSurface, n: int, spread: float) -> np.ndarray:
    """Points on random facets moved along the normal by up to ``±spread``, plus a few anywhere."""
    d = surf.dim
    j = rng.integers(surf.n_facets, size=n)
    w = rng.dirichlet(np.ones(d), size=n)
    on = np.einsum("pa,pad->pd", w, surf.nodes[surf.facets[j]])
    x = on + rng.uniform(-spread, spread, (n, 1)) * surf.normals()[j] + rng.normal(0, 0.2 * spread, (n, d))
    k = max(1, n // 10)
    lo, hi = surf.nodes.min(axis=0) - spread, surf.nodes.max(axis=0) + spread
    x[:k] = rng.uniform(lo, hi, (k, d))
    return x


CASE = st.tuples(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]))


@settings(max_examples=40, deadline=None)
@given(case=CASE)
def test_closest_points_and_normals_match_the_reference(case):
    seed, dim = case
    rng = np.random.default_rng(seed)
    surf = random_surface(rng, dim)
    x = slaves_near(rng, surf, 60, 0.5)
    which = rng.integers(surf.n_facets, size=60)
    got, ref = closest_points(x, surf.nodes, surf.facets, which), closest_points_reference(x, surf.nodes, surf.facets,
                                                                                          which)
    np.testing.assert_allclose(facet_normals(surf.nodes, surf.facets), facet_normals_reference(surf.nodes, surf.facets),
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(got.points, ref.points, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.weights, ref.weights, rtol=0, atol=1e-10)
    np.testing.assert_allclose(got.distance, ref.distance, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.normals, ref.normals, rtol=0, atol=1e-14)
    assert np.all(got.weights >= 0) and np.allclose(got.weights.sum(axis=1), 1.0, atol=1e-14)
    # the region agrees wherever the closest point is not within round-off of a border
    clear = np.min(np.where(ref.weights > 1e-9, ref.weights, 1.0), axis=1) > 1e-9
    clear &= np.sum(ref.weights > 1e-9, axis=1) == np.sum(got.weights > 1e-9, axis=1)
    np.testing.assert_array_equal(got.region[clear], ref.region[clear])
    inside = np.sum(ref.weights > 1e-9, axis=1)
    expected = np.where(inside == dim, INTERIOR, np.where(inside == 1, VERTEX, EDGE))
    np.testing.assert_array_equal(got.region[clear], expected[clear])
    # no other point of the facet is closer (sampled)
    for i in range(0, 60, 7):
        w = rng.dirichlet(np.ones(dim), size=200)
        pts = np.einsum("pa,ad->pd", w, surf.nodes[surf.facets[which[i]]])
        assert np.min(np.linalg.norm(pts - x[i], axis=1)) >= np.linalg.norm(got.points[i] - x[i]) - 1e-12


@settings(max_examples=40, deadline=None)
@given(case=CASE, margin=st.floats(0.0, 0.4))
def test_broad_phase_finds_the_same_pairs_as_brute_force(case, margin):
    seed, dim = case
    rng = np.random.default_rng(seed)
    surf = random_surface(rng, dim)
    x = slaves_near(rng, surf, 200, 0.6)
    indptr, indices = candidate_pairs(x, surf.nodes, surf.facets, margin)
    ref_ptr, ref_idx = candidate_pairs_reference(x, surf.nodes, surf.facets, margin)
    np.testing.assert_array_equal(indptr, ref_ptr)
    np.testing.assert_array_equal(indices, ref_idx)
    # and it misses no facet within the margin (the exact distance)
    s = np.repeat(np.arange(len(x)), surf.n_facets)
    j = np.tile(np.arange(surf.n_facets), len(x))
    near = np.linalg.norm(closest_points_reference(x[s], surf.nodes, surf.facets, j).points - x[s], axis=1) <= margin
    found = set(zip(np.repeat(np.arange(len(x)), np.diff(indptr)).tolist(), indices.tolist()))
    assert set(zip(s[near].tolist(), j[near].tolist())) <= found


def test_broad_phase_boxes_are_closed():
    """A slave exactly ``margin`` from a facet, on the face of its grown box, is a candidate."""
    surf = floor(2)
    x = np.array([[0.0, 0.25], [0.0, -0.25], [1.25, 0.0], [0.0, 0.2500001], [-1.2500001, 0.0]])
    for find in (candidate_pairs, candidate_pairs_reference):
        assert np.diff(find(x, surf.nodes, surf.facets, 0.25)[0]).tolist() == [1, 1, 1, 0, 0]


@pytest.mark.parametrize("layout", ["a fine mesh", "scattered tiny facets"])
def test_broad_phase_on_large_and_sparse_meshes(layout, rng):
    """A 1800-triangle height field with 5000 slaves (some far away), and 40 tiny triangles
    scattered over a 100 m cube, where a grid of the facets' size would have 1e10 cells and is
    coarsened to the cap of max(8 k, 4096) cells."""
    if layout == "a fine mesh":
        n = 30
        gx, gy = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
        nodes = np.column_stack([gx.ravel(), gy.ravel(), 0.01 * rng.normal(size=gx.size)])
        idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
        facets = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
        x = np.column_stack([rng.uniform(-0.1, 1.1, (5000, 2)), rng.uniform(-0.05, 0.05, 5000)])
        x[:100] += 50.0
    else:
        corners = rng.uniform(0, 100, (40, 1, 3)) + rng.uniform(0, 0.02, (40, 3, 3))
        nodes, facets = corners.reshape(-1, 3), np.arange(120).reshape(40, 3)
        x = np.repeat(corners.mean(axis=1), 50, axis=0) + rng.normal(0, 0.01, (2000, 3))
    got = candidate_pairs(x, nodes, facets, 0.01)
    ref = candidate_pairs_reference(x, nodes, facets, 0.01)
    np.testing.assert_array_equal(got[0], ref[0])
    np.testing.assert_array_equal(got[1], ref[1])
    assert got[1].size > 1000
    empty = candidate_pairs(np.zeros((0, 3)), nodes, facets, 0.01)
    assert empty[0].tolist() == [0] and empty[1].size == 0


def assert_same_result(got, ref, dim: int, surf: ContactSurface) -> None:
    scale = max(float(np.abs(ref.slave_forces).max(initial=0.0)), 1.0)
    np.testing.assert_allclose(got.slave_forces, ref.slave_forces, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(got.master_forces, ref.master_forces, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(got.total_force, ref.total_force, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(got.moment, ref.moment, rtol=0, atol=1e-11 * scale)
    finite = np.isfinite(ref.gaps)
    differ = np.isfinite(got.gaps) != finite
    if dim == 3:
        # a slave in front of an edge or corner shared by triangles is a tie that round-off may
        # break either way: one side finds a primary contact with an inactive gap (>= 0), the
        # other none (seen with seed 1909855720: gap 0.025 against inf); forces are equal either way
        assert np.all(np.where(finite, ref.gaps, got.gaps)[differ] >= 0.0)
    else:
        assert not differ.any()
    both = finite & np.isfinite(got.gaps)
    np.testing.assert_allclose(got.gaps[both], ref.gaps[both], rtol=0, atol=1e-12)
    assert (got.contacts, got.active_slaves) == (ref.contacts, ref.active_slaves)
    assert got.max_penetration == pytest.approx(ref.max_penetration, abs=1e-12)
    assert got.stable_dt == pytest.approx(ref.stable_dt, rel=1e-10)
    np.testing.assert_array_equal(got.pair_slave, ref.pair_slave)
    if dim == 2:  # in 3D an edge shared by two triangles is a tie that round-off may break either way
        np.testing.assert_array_equal(got.pair_facet, ref.pair_facet)
    np.testing.assert_allclose(got.pair_gap, ref.pair_gap, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.pair_force, ref.pair_force, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(got.pair_stiffness, ref.pair_stiffness, rtol=1e-13, atol=0)
    assert got.stored_energy == pytest.approx(ref.stored_energy, rel=1e-10, abs=1e-300)
    np.testing.assert_allclose(got.pair_normal, ref.pair_normal, rtol=0, atol=1e-9)
    assert got.pair_weights.shape == ref.pair_weights.shape == (got.contacts, dim)
    for pairs in (got, ref):  # the slave forces are the sums of their contacts
        summed = np.zeros_like(pairs.slave_forces)
        np.add.at(summed, pairs.pair_slave, pairs.pair_force[:, None] * pairs.pair_normal)
        np.testing.assert_allclose(summed, pairs.slave_forces, rtol=0, atol=1e-12 * scale)
    _, xc_got, fc_got = got.contact_points(surf.nodes, surf.facets)
    _, xc_ref, fc_ref = ref.contact_points(surf.nodes, surf.facets)
    np.testing.assert_allclose(xc_got, xc_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fc_got, fc_ref, rtol=0, atol=1e-11 * scale)


@settings(max_examples=40, deadline=None)
@given(case=CASE, thickness=st.floats(0.0, 0.2), reach_factor=st.floats(1.05, 4.0),
       rigid=st.booleans(), damping=st.floats(0.0, 0.5), feature=st.floats(5.0, 90.0))
def test_penalty_kernel_matches_the_reference(case, thickness, reach_factor, rigid, damping, feature):
    seed, dim = case
    rng = np.random.default_rng(seed)
    surf = random_surface(rng, dim)
    reach = max(reach_factor * thickness, 0.05)
    x = slaves_near(rng, surf, 150, thickness + reach)
    n, m = len(x), surf.n_nodes
    args = (x, rng.normal(0, 1, (n, dim)), rng.uniform(0.01, 1.0, n), surf.nodes, rng.normal(0, 1, (m, dim)),
            None if rigid else rng.uniform(0.01, 1.0, m), surf.facets)
    kw = dict(dt_ref=1e-3, thickness=thickness, reach=reach, alpha=0.1, damping=damping, feature_angle=feature,
              centre=rng.uniform(-1, 1, dim))
    got, ref = penalty_forces(*args, **kw), penalty_forces_reference(*args, **kw)
    assert_same_result(got, ref, dim, surf)


@pytest.mark.parametrize("dim", [2, 3])
def test_penalty_kernel_matches_the_reference_in_a_crowded_tank(dim, rng):
    """Many slaves in the corners and edges of a tank: secondary contacts everywhere."""
    surf = ContactSurface.tank(np.zeros(dim), np.ones(dim), open_top=False)
    x = rng.uniform(-0.01, 0.04, (500, dim))
    x[::2] = 1 - x[::2]
    args = (x, rng.normal(0, 1, (500, dim)), 0.1, surf.nodes, None, None, surf.facets)
    kw = dict(dt_ref=1e-4, thickness=0.02, reach=0.04)
    got, ref = penalty_forces(*args, **kw), penalty_forces_reference(*args, **kw)
    assert np.bincount(got.pair_slave).max() == dim  # some slaves touch d walls
    assert_same_result(got, ref, dim, surf)
    given_pairs = candidate_pairs(x, surf.nodes, surf.facets, search_margin(0.02, 0.04))
    again = penalty_forces(*args, **kw, candidates=given_pairs)
    np.testing.assert_array_equal(again.slave_forces, got.slave_forces)



def test_the_narrow_phase_compiles_once_for_every_flavour_of_input(rng):
    """Scalar or per-node masses, read-only or writable arrays (what ``np.broadcast_to`` and a
    memory-mapped file give), given or computed pairs, rigid or deformable master, 2D or 3D: one
    compiled narrow phase serves them all (each new specialisation costs about a minute)."""
    from mlsgalerkin.contact import penalty

    def read_only(a):
        a = np.array(a)
        a.flags.writeable = False
        return a

    for dim in (2, 3):
        surf = random_surface(rng, dim)
        x = slaves_near(rng, surf, 40, 0.1)
        n, m = len(x), surf.n_nodes
        v = rng.normal(0, 1, (n, dim))
        kw = dict(dt_ref=1e-3, thickness=0.05, reach=0.1)
        pairs = candidate_pairs(x, surf.nodes, surf.facets, search_margin(0.05, 0.1))
        penalty_forces(x, v, 0.1, surf.nodes, None, None, surf.facets, **kw)
        penalty_forces(x, v, rng.uniform(0.1, 1, n), surf.nodes, np.zeros(dim), 2.0, surf.facets, **kw)
        penalty_forces(read_only(x), read_only(v), read_only(np.full(n, 0.1)), read_only(surf.nodes),
                       read_only(np.zeros((m, dim))), read_only(np.ones(m)), read_only(surf.facets), **kw,
                       centre=read_only(np.ones(dim)), candidates=tuple(read_only(p) for p in pairs))
    assert len(penalty._contacts.signatures) == 1, penalty._contacts.signatures
    assert len(penalty._gather.signatures) == 1, penalty._gather.signatures


# ------------------------------------------------------------------ the two-body interaction
class PointSolver(Solver):
    """A stand-in solver holding one body's nodes (and segments) at rest, recording forces."""

    key = "points"

    def __init__(self, name, x, m, segments=None, dt=1e-4):
        self.name, self.x, self.m, self.dt = name, np.asarray(x, float), m, dt
        self.segments = np.zeros((0, self.x.shape[1]), dtype=np.int64) if segments is None else segments
        self.received = np.zeros_like(self.x)

    @property
    def state(self):
        return None

    def start(self): ...

    def stable_time_step(self):
        return self.dt

    def begin_step(self, t, dt): ...

    def end_step(self, t, dt): ...

    def surface(self, body):
        return Surface(body, self.x, np.zeros_like(self.x), self.segments, self.m)

    def add_surface_forces(self, body, forces):
        self.received += forces

    def checkpoint(self):
        return {}, {}

    def restore(self, arrays, meta): ...

    def summary(self):
        return {}


def test_penalty_contact_exchanges_equal_and_opposite_forces_and_restarts_with_its_stiffness():
    plate = ContactSurface.polyline([(1.0, 0.0), (0.0, 0.0)])
    water = PointSolver("water", [[0.25, 0.003], [0.5, 0.004], [0.75, 0.02]], np.full(3, 0.1), dt=2e-4)
    wall = PointSolver("plate", plate.nodes, None, plate.facets, dt=1e-4)  # rigid (no masses)
    contact = PenaltyContact("water", "plate", thickness=0.005, moment_about=(0.0, 0.0))
    assert contact.stable_time_step() == math.inf
    contact.exchange(0.0, water, wall)
    k = DEFAULT_ALPHA * 0.1 / 1e-4**2  # dt_ref: the smaller of the solvers' steps, fixed now
    np.testing.assert_allclose(water.received[:, 1], [k * 0.002, k * 0.001, 0.0], rtol=1e-12)
    np.testing.assert_allclose(wall.received.sum(axis=0), -water.received.sum(axis=0), rtol=1e-14)
    assert contact.stable_time_step() == pytest.approx(rigid_time_step(DEFAULT_ALPHA, 0.03, 1e-4, 2))
    assert contact.last["contacts"] == 2 and contact.last["moment"] == pytest.approx(-k * (0.25 * 0.002 + 0.5 * 0.001))
    state = json.loads(json.dumps(contact.state_dict()))
    # a fresh instance after a restart keeps the stiffness even though the solvers' steps changed
    water.dt, wall.dt = 5e-5, 5e-5
    again = PenaltyContact("water", "plate", thickness=0.005, moment_about=(0.0, 0.0))
    again.load_state_dict(state)
    before = water.received.copy()
    again.exchange(1e-4, water, wall)
    np.testing.assert_allclose(water.received - before, before, rtol=1e-15)
    assert again.exchanges == 2 and again.summary()["dt_ref_s"] == 1e-4
    json.dumps(again.summary())
    # a deformable master (with nodal masses) gets the reduced mass and the node bound
    wall.m = np.array([0.1, 0.1])
    soft = PenaltyContact("water", "plate", thickness=0.005, dt_ref=1e-4)
    soft.exchange(0.0, water, wall)
    assert soft.summary()["master_rigid"] is False and soft.stable_time_step() < contact.stable_time_step()


def test_penalty_contact_refuses_a_master_without_segments_and_bad_parameters():
    from mlsgalerkin.fluid import FluidBody, Phase
    from mlsgalerkin.scene import Scene

    water = PointSolver("water", [[0.25, 0.003]], np.full(1, 0.1))
    with pytest.raises(ValueError, match="exposes no segments"):
        PenaltyContact("water", "other", thickness=0.005).exchange(0.0, water, water)
    scene = Scene([FluidBody.block("water", (0, 0), (0.05, 0.05), 0.01, [Phase("w", 1000.0)])], [], t_end=0.1)
    cases = [
        (dict(thickness=0.005, alpha=-1.0), "alpha (the stiffness factor"),
        (dict(thickness=0.005, alpha=2.0), "keep alpha <= 1"),
        (dict(thickness=0.005, damping=1.5), "damping"),
        (dict(thickness=-0.005), "thickness"),
        (dict(thickness=0.005, reach=0.004), "must exceed the thickness"),
        (dict(thickness=0.0), "give reach="),
        (dict(thickness=0.005, feature_angle=0.0), "feature_angle"),
        (dict(thickness=0.005, dt_ref=-1.0), "dt_ref"),
        (dict(thickness=0.005, moment_about=(0, 0, 0)), "moment_about"),
        (dict(thickness=float("nan")), "thickness"),
    ]
    for kw, fragment in cases:
        problems = PenaltyContact("water", "plate", **kw).problems(scene)
        assert any(fragment in p for p in problems), (kw, problems)
        assert any("no body named 'plate'" in p for p in problems)
    assert any("same body" in p for p in PenaltyContact("water", "water", thickness=0.01).problems(scene))


@pytest.mark.parametrize("kw, fragment", [
    (dict(alpha=0.0), "alpha"),
    (dict(alpha=float("inf")), "alpha"),
    (dict(damping=-0.1), "damping"),
    (dict(thickness=-1.0), "thickness"),
    (dict(reach=0.004), "must exceed the thickness"),
    (dict(dt_ref=0.0), "dt_ref"),
    (dict(dt_ref=None), "dt_ref is required"),
    (dict(feature_angle=120.0), "feature_angle"),
    (dict(alpha=True), "alpha"),
])
def test_the_kernel_refuses_bad_parameters_clearly(kw, fragment):
    args = dict(dt_ref=DT, thickness=G0, reach=REACH)
    args.update(kw)
    surf = floor(2)
    with pytest.raises(ValueError, match=None) as info:
        penalty_forces(np.zeros((1, 2)), np.zeros((1, 2)), 0.1, surf.nodes, None, None, surf.facets, **args)
    assert fragment in str(info.value)


@pytest.mark.parametrize("call, fragment", [
    (lambda s: penalty_forces(np.zeros((1, 3)), np.zeros((1, 3)), 0.1, s.nodes, None, None, s.facets, dt_ref=DT,
                              thickness=G0, reach=REACH), "share one dimension"),
    (lambda s: penalty_forces(np.zeros(2), np.zeros(2), 0.1, s.nodes, None, None, s.facets, dt_ref=DT,
                              thickness=G0, reach=REACH), "(n, 2) or (n, 3)"),
    (lambda s: penalty_forces(np.zeros((1, 2)), np.zeros((1, 2)), 0.0, s.nodes, None, None, s.facets, dt_ref=DT,
                              thickness=G0, reach=REACH), "masses must be positive"),
    (lambda s: penalty_forces(np.zeros((1, 2)), np.zeros((1, 2)), 0.1, s.nodes, None, [1.0, -1.0], s.facets,
                              dt_ref=DT, thickness=G0, reach=REACH), "masses must be positive"),
    (lambda s: penalty_forces(np.zeros((1, 2)), np.zeros((1, 2)), 0.1, s.nodes, None, None, s.facets + 1,
                              dt_ref=DT, thickness=G0, reach=REACH), "must lie in [0, 2)"),
])
def test_the_kernel_refuses_inconsistent_arrays(call, fragment):
    with pytest.raises(ValueError) as info:
        call(floor(2))
    assert fragment in str(info.value)


def test_the_old_import_paths_of_the_interactions_work_for_a_release_and_name_the_new_one():
    """``PenaltyContact`` and ``StructureCoupling`` moved to :mod:`mlsgalerkin.interactions`; the
    old names and module paths give the same classes with a ``DeprecationWarning`` that names
    the new import (checked in a fresh interpreter: each old name warns once per process)."""
    import subprocess
    import sys

    code = """
import warnings
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    import mlsgalerkin.contact, mlsgalerkin.fluid
    assert not caught, [str(w.message) for w in caught]   # importing the old packages is silent
    from mlsgalerkin.interactions import PenaltyContact, StructureCoupling, riding_kinematics
    from mlsgalerkin.contact import PenaltyContact as a
    from mlsgalerkin.contact.interaction import PenaltyContact as b
    from mlsgalerkin.fluid import StructureCoupling as c
    from mlsgalerkin.fluid.coupling import StructureCoupling as d, riding_kinematics as e
assert a is b is PenaltyContact and c is d is StructureCoupling and e is riding_kinematics
for w in caught:
    assert issubclass(w.category, DeprecationWarning) and "from mlsgalerkin.interactions import" in str(w.message)
print(sorted({str(w.message).split(" has moved")[0] for w in caught}))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str(sorted([
        "mlsgalerkin.contact.PenaltyContact", "mlsgalerkin.contact.interaction.PenaltyContact",
        "mlsgalerkin.fluid.StructureCoupling", "mlsgalerkin.fluid.coupling.StructureCoupling",
        "mlsgalerkin.fluid.coupling.riding_kinematics"]))


def test_the_penalty_kernel_is_called_from_one_place():
    """Penalty contact between bodies and the fluid's penalty walls share one wrapper of the
    kernel (``contact.law.PenaltyLaw``: the parameters, the reference step fixed once, the
    stored energy summed): no other module of the package calls ``penalty_forces``."""
    import ast
    from pathlib import Path

    import mlsgalerkin
    from mlsgalerkin.contact.law import PenaltyLaw
    from mlsgalerkin.fluid import PenaltyWalls

    root = Path(mlsgalerkin.__file__).parent
    callers = set()
    for path in root.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", None)) == "penalty_forces":
                callers.add(path.relative_to(root).as_posix())
    assert callers == {"contact/law.py"}, callers
    assert isinstance(PenaltyContact("water", "plate", thickness=0.005).law, PenaltyLaw)
    assert PenaltyWalls().law is None  # its lengths need the fluid's spacing: made at set-up


def test_a_penalty_law_fixes_its_reference_step_once_and_sums_the_energy_of_an_evaluation():
    floor = ContactSurface.polyline([(1.0, 0.0), (-1.0, 0.0)])
    law = PenaltyLaw(thickness=0.005, reach=0.01)
    assert law.time_step_limit(2) == math.inf
    with pytest.raises(ValueError, match="no step: inf"):
        law.fix_reference_step(lambda: math.inf, lambda dt: f"no step: {dt}")
    assert law.fix_reference_step(lambda: 1e-4, str) == 1e-4
    assert law.fix_reference_step(lambda: 5e-5, str) == 1e-4   # fixed once
    x = np.array([[0.0, 0.004], [0.5, 0.003]])
    law.begin()
    one = law.forces(x[:1], np.zeros((1, 2)), 0.1, floor.nodes, None, None, floor.facets)
    two = law.forces(x[1:], np.zeros((1, 2)), 0.1, floor.nodes, None, None, floor.facets)
    assert law.energy == one.stored_energy + two.stored_energy > 0
    law.begin()
    assert law.energy == 0.0
    assert law.time_step_limit(2) == rigid_time_step(DEFAULT_ALPHA, DEFAULT_DAMPING, 1e-4, 2)
