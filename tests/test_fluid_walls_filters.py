"""Wall-state extrapolation and density filters: compiled kernels against their numpy
references, hydrostatic extrapolation, linear reproduction and a sharp two-phase jump."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.fluid import lattice, wall_box
from mlsgalerkin.fluid.filters import mls_ratio_filter, mls_ratio_filter_reference
from mlsgalerkin.fluid.walls import (
    SLIP_MODES,
    extrapolate_wall_state,
    extrapolate_wall_state_reference,
    no_slip_wall_velocity,
    no_slip_wall_velocity_reference,
)
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors

DX = 0.01
KERNEL = get_kernel("cubic_spline")


def _tank_cloud(rng, W=0.2, H=0.1, jitter=0.2, h_spread=0.1):
    """Jittered fluid lattice in [0, W] × [0, H] plus a 3-layer wall box around it (walls
    reach up to 2H, so the upper wall particles have no fluid in reach)."""
    fluid = lattice((0.0, 0.0), (W, H), DX)
    fluid = fluid + rng.uniform(-jitter, jitter, fluid.shape) * DX
    walls = wall_box((0.0, 0.0), (W, 2 * H), DX, layers=3)
    x = np.ascontiguousarray(np.vstack([fluid, walls.positions]))
    n_f, n = len(fluid), len(x)
    h = 1.3 * DX * (1.0 + h_spread * rng.random(n))
    table = find_neighbors(x, x, radius=KERNEL.support * h.max() * 1.0001)
    return x, n_f, n, h, walls, table


def _wall_args(rng, x, n_f, n, h, walls, table, g):
    is_fluid = np.zeros(n, dtype=bool)
    is_fluid[:n_f] = True
    v = rng.standard_normal((n, 2))
    rho = 1000.0 * (1.0 + 0.02 * rng.standard_normal(n))
    p = 1e3 * rng.standard_normal(n)
    n_w = n - n_f
    wall_v = np.ascontiguousarray(np.broadcast_to(rng.standard_normal(2), (n_w, 2)))
    return dict(
        wall_ids=np.arange(n_f, n, dtype=np.int64), indptr=table.indptr, indices=table.indices,
        x=x, v=v,
        rho=rho, p=p, h=h, is_fluid=is_fluid, kernel=KERNEL, g_minus_a=np.asarray(g, dtype=float),
        wall_velocity=wall_v, normals=walls.normals, rho_ref=np.full(n_w, 1000.0),
    )


def _reached(args) -> np.ndarray:
    """Wall particles with at least one fluid particle f within its support ``κ h_f``."""
    out = []
    for w in args["wall_ids"]:
        nb = args["indices"][args["indptr"][w]:args["indptr"][w + 1]]
        nb = nb[args["is_fluid"][nb]]
        r = np.linalg.norm(args["x"][nb] - args["x"][w], axis=1)
        out.append(bool(np.any(r < KERNEL.support * args["h"][nb])))
    return np.array(out)


def test_wall_extrapolation_compiles_once_for_a_shared_or_per_wall_gravity(rng):
    """Gravity given once ``(d,)`` (broadcast to a read-only view) or per wall particle
    ``(n_w, d)``: the one compiled kernel serves both."""
    from mlsgalerkin.fluid import walls as wall_module

    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=(0.0, -9.81))
    shared = extrapolate_wall_state(**args, slip="no_slip")
    args["g_minus_a"] = np.tile(args["g_minus_a"], (n - n_f, 1))
    per_wall = extrapolate_wall_state(**args, slip="no_slip")
    for a, b in zip(shared, per_wall, strict=True):
        np.testing.assert_array_equal(a, b)
    assert len(wall_module._extrapolate.signatures) == 1, wall_module._extrapolate.signatures


@pytest.mark.parametrize("slip", sorted(SLIP_MODES))
def test_wall_extrapolation_matches_reference(rng, slip):
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=(0.3, -9.81))
    p, rho, v = extrapolate_wall_state(**args, slip=slip)
    pr, rhor, vr = extrapolate_wall_state_reference(**args, slip=slip)
    np.testing.assert_allclose(p, pr, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(rho, rhor, rtol=1e-13)
    np.testing.assert_allclose(v, vr, rtol=1e-12, atol=1e-12)
    # the configuration exercises both branches: walls in reach of fluid and out of reach
    reached = _reached(args)
    assert reached.any() and (~reached).any()
    assert np.all(p[~reached] == 0.0) and np.all(rho[~reached] == 1000.0)
    np.testing.assert_array_equal(v[~reached], args["wall_velocity"][~reached])
    if slip == "fixed":
        np.testing.assert_array_equal(v, args["wall_velocity"])


def test_free_slip_mirrors_the_normal_velocity(rng):
    """Free slip: (v_w − v_wall)·n = −(ṽ − v_wall)·n, tangential part continued; no slip:
    v_w + ṽ = 2 v_wall (the average vanishes relative to the wall)."""
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=(0.0, -9.81))
    _, _, v_free = extrapolate_wall_state(**args, slip="free_slip")
    _, _, v_no = extrapolate_wall_state(**args, slip="no_slip")
    vw = args["wall_velocity"]
    nrm = walls.normals
    v_tilde = 2 * vw - v_no  # the kernel-averaged fluid velocity
    rel_t, rel_f = v_tilde - vw, v_free - vw
    normal = lambda u: np.einsum("ij,ij->i", u, nrm)  # noqa: E731
    np.testing.assert_allclose(normal(rel_f), -normal(rel_t), atol=1e-12)
    tangential = lambda u: u - normal(u)[:, None] * nrm  # noqa: E731
    np.testing.assert_allclose(tangential(rel_f), tangential(rel_t), atol=1e-12)


def test_hydrostatic_extrapolation_is_exact(rng):
    """A fluid at rest with p = ρ0 g (H − y) and uniform ρ0: every wall particle in reach
    gets p_w = ρ0 g (H − y_w), the hydrostatic pressure continued into the wall, for any
    kernel weights (the extrapolation reproduces the linear field exactly)."""
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=(0.0, -9.81))
    H, rho0, g = 0.1, 1000.0, 9.81
    args["rho"] = np.full(n, rho0)
    args["p"] = rho0 * g * (H - x[:, 1])
    args["v"] = np.zeros((n, 2))
    args["wall_velocity"] = np.zeros((n - n_f, 2))
    p_w, rho_w, v_w = extrapolate_wall_state(**args, slip="free_slip")
    reached = _reached(args)
    assert reached.sum() > 0.4 * reached.size  # the walls reach twice the fluid depth
    xw = x[n_f:]
    np.testing.assert_allclose(p_w[reached], rho0 * g * (H - xw[reached, 1]), rtol=1e-12, atol=1e-9)
    assert p_w[reached].max() > rho0 * g * H  # below the floor: deeper than the fluid
    np.testing.assert_allclose(rho_w, rho0, rtol=1e-14)  # a weighted mean of a constant, to rounding
    np.testing.assert_allclose(v_w, 0.0, atol=1e-15)


def test_accelerating_wall_extrapolation_is_exact(rng):
    """A fluid at rest relative to a wall accelerating at ``a`` has ``∇p = ρ0 (g − a)``; the
    extrapolation with ``g − a`` per wall particle continues that linear pressure exactly, and
    the compiled kernel agrees with the reference for per-particle values."""
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    n_w = n - n_f
    g, a, rho0 = np.array([0.0, -9.81]), np.array([2.5, 0.7]), 1000.0
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=np.broadcast_to(g - a, (n_w, 2)).copy())
    args["rho"] = np.full(n, rho0)
    args["p"] = rho0 * (x @ (g - a)) + 3.0e3
    p_w, _, _ = extrapolate_wall_state(**args, slip="fixed")
    reached = _reached(args)
    np.testing.assert_allclose(p_w[reached], (rho0 * (x[n_f:] @ (g - a)) + 3.0e3)[reached], rtol=1e-12, atol=1e-8)
    # per-particle values differ: the kernel and the reference agree
    args["g_minus_a"] = rng.standard_normal((n_w, 2))
    p1, _, _ = extrapolate_wall_state(**args, slip="no_slip")
    p2, _, _ = extrapolate_wall_state_reference(**args, slip="no_slip")
    np.testing.assert_allclose(p1, p2, rtol=1e-12, atol=1e-9)


def _no_slip_args(args):
    return {k: args[k] for k in ("wall_ids", "indptr", "indices", "x", "v", "h", "is_fluid", "kernel",
                                 "wall_velocity", "normals")} | {"spacing": DX}


def test_no_slip_wall_velocity_matches_reference(rng):
    """The compiled per-particle no-slip fit against the numpy one, in a jittered tank with
    corners (diagonal normals), random velocities and wall particles out of the fluid's reach."""
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _no_slip_args(_wall_args(rng, x, n_f, n, h, walls, table, g=(0.0, -9.81)))
    v, depth = no_slip_wall_velocity(**args)
    vr, depthr = no_slip_wall_velocity_reference(**args)
    np.testing.assert_allclose(depth, depthr, rtol=1e-13)
    np.testing.assert_allclose(v, vr, rtol=1e-9, atol=1e-9)
    reached = _reached({**args, "wall_ids": args["wall_ids"]})
    assert reached.any() and (~reached).any()


def test_no_slip_falls_back_to_the_shepard_mirror_in_corners(rng):
    """A wall particle with a wall particle in reach whose normal is turned by more than 25°
    (the corners of a wall box) gets 2 v_wall − ṽ, as extrapolate_wall_state's no_slip mode."""
    x, n_f, n, h, walls, table = _tank_cloud(rng)
    args = _wall_args(rng, x, n_f, n, h, walls, table, g=(0.0, -9.81))
    v_fit, _ = no_slip_wall_velocity(**_no_slip_args(args))
    _, _, v_mirror = extrapolate_wall_state(**args, slip="no_slip")
    xw, nw = x[n_f:], walls.normals
    d = np.linalg.norm(xw[:, None] - xw[None], axis=2)
    corner = np.any((d < KERNEL.support * h[n_f:, None]) & (nw @ nw.T < 0.9), axis=1)
    assert corner.sum() >= 8 and (~corner).sum() > corner.sum()
    np.testing.assert_allclose(v_fit[corner], v_mirror[corner], rtol=1e-12, atol=1e-12)
    assert np.abs(v_fit[~corner] - v_mirror[~corner]).max() > 0.1


@pytest.mark.parametrize("jitter", [0.0, 0.2])
def test_no_slip_continues_a_shear_profile_into_every_layer(rng, jitter):
    """Over a floor (three layers at depths ½, 3/2, 5/2 Δx) moving at U, a fluid with
    u = U + a y + b y² (Couette and Poiseuille are of this form) gives each wall particle
    u(y_w) — the profile continued through the wall velocity — and no normal velocity. The
    Shepard mirror 2U − ṽ (Adami, Hu & Adams 2012) gave the deepest layer U."""
    fluid = lattice((0.0, 0.0), (0.3, 0.1), DX)
    fluid = fluid + rng.uniform(-jitter, jitter, fluid.shape) * DX
    floor = np.column_stack([np.tile(np.arange(30) * DX + 0.5 * DX, 3), np.repeat(-(np.arange(3) + 0.5) * DX, 30)])
    x = np.ascontiguousarray(np.vstack([fluid, floor]))
    n_f, n = len(fluid), len(x)
    h = np.full(n, 1.3 * DX)
    table = find_neighbors(x, x, radius=KERNEL.support * 1.3 * DX * 1.0001)
    U, a, b = 0.4, 30.0, -120.0
    v = np.column_stack([U + a * x[:, 1] + b * x[:, 1] ** 2, np.zeros(n)])
    is_fluid = np.arange(n) < n_f
    n_w = n - n_f
    args = {"wall_ids": np.arange(n_f, n, dtype=np.int64), "indptr": table.indptr, "indices": table.indices,
            "x": x, "v": v, "h": h, "is_fluid": is_fluid, "kernel": KERNEL, "spacing": DX,
            "wall_velocity": np.tile([U, 0.0], (n_w, 1)), "normals": np.tile([0.0, 1.0], (n_w, 1))}
    v_w, depth = no_slip_wall_velocity(**args)
    y_w = floor[:, 1]
    np.testing.assert_allclose(depth, -y_w, rtol=1e-12)
    inner = np.abs(floor[:, 0] - 0.15) < 0.1        # away from the ends of the floor
    np.testing.assert_allclose(v_w[inner, 0], (U + a * y_w + b * y_w**2)[inner], rtol=0, atol=1e-9)
    np.testing.assert_allclose(v_w[:, 1], 0.0, atol=1e-9)


# ------------------------------------------------------------------------------- filters
def _filter_cloud(rng, jitter=0.25):
    fluid = lattice((0.0, 0.0), (0.2, 0.2), DX)
    fluid = fluid + rng.uniform(-jitter, jitter, fluid.shape) * DX
    walls = wall_box((0.0, 0.0), (0.2, 0.3), DX, layers=3).positions
    x = np.ascontiguousarray(np.vstack([fluid, walls]))
    n_f, n = len(fluid), len(x)
    h = np.full(n, 1.3 * DX)
    nb = find_neighbors(x, x, radius=KERNEL.support * 1.3 * DX)
    table = evaluate_shape_functions(x, x, h, nb, KERNEL, 1, "mls")
    return x, n_f, n, table


def test_mls_filter_matches_reference(rng):
    x, n_f, n, table = _filter_cloud(rng)
    rho0 = np.where(x[:, 0] < 0.1, 1000.0, 1500.0)
    rho = rho0 * (1.0 + 0.01 * rng.standard_normal(n))
    expected = mls_ratio_filter_reference(table, rho, rho0, n_f)
    out = rho.copy()
    mls_ratio_filter(table, out, rho0, n_f)
    np.testing.assert_allclose(out[:n_f], expected, rtol=1e-13)
    np.testing.assert_array_equal(out[n_f:], rho[n_f:])  # wall rows untouched


def test_mls_filter_reproduces_a_linear_density(rng):
    """Interior points (every neighbour a fluid node, so Σ_F N_j = 1) reproduce
    ρ = ρ0 (1 + a x + b y) exactly; near the walls the fluid-only sums are renormalised."""
    x, n_f, n, table = _filter_cloud(rng)
    rho0 = np.full(n, 1000.0)
    rho = rho0 * (1.0 + 0.3 * x[:, 0] - 0.2 * x[:, 1])
    out = rho.copy()
    mls_ratio_filter(table, out, rho0, n_f)
    rows = [table.indices[table.indptr[i]:table.indptr[i + 1]] for i in range(n_f)]
    interior = np.array([np.all(r < n_f) for r in rows])
    interior &= table.order[:n_f] == 1
    assert interior.sum() > 0.5 * n_f
    np.testing.assert_allclose(out[:n_f][interior], rho[:n_f][interior], rtol=1e-13)


def test_mls_filter_keeps_a_two_phase_jump_sharp(rng):
    """ρ0 = 1000 | 1500 with ρ/ρ0 = 1 everywhere: the filtered ratio is exactly 1, so the
    density jump stays bit-for-bit sharp (a filter of ρ itself would smear it over 2h)."""
    x, n_f, n, table = _filter_cloud(rng)
    rho0 = np.where(x[:, 0] < 0.1, 1000.0, 1500.0)
    out = rho0.copy()
    mls_ratio_filter(table, out, rho0, n_f)
    np.testing.assert_array_equal(out, rho0)


def test_no_slip_wall_keeps_the_fit_tangential_and_the_mirror_normal():
    """The no-slip wall velocity: tangential part from the fit, normal part from the mirror."""
    from mlsgalerkin.fluid.walls import with_normal_component_of

    n = np.array([[0.0, -1.0], [1.0, 0.0], [np.sqrt(0.5), np.sqrt(0.5)]])
    v_fit = np.array([[0.3, 0.2], [0.1, -0.4], [1.0, 0.0]])
    v_mirror = np.array([[-0.5, -0.1], [0.7, 0.9], [0.0, 0.0]])
    v = with_normal_component_of(v_fit, v_mirror, n)
    np.testing.assert_allclose(np.sum(v * n, axis=1), np.sum(v_mirror * n, axis=1), atol=1e-15)
    t = n[:, ::-1] * np.array([1.0, -1.0])
    np.testing.assert_allclose(np.sum(v * t, axis=1), np.sum(v_fit * t, axis=1), atol=1e-15)
