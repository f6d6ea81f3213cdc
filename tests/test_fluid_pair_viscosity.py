"""Monaghan pair artificial viscosity: agreement, conservation, dissipation, time-step limit."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.fluid.pair_viscosity import (
    monaghan_viscosity_force,
    monaghan_viscosity_force_reference,
)
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors


def _cloud(rng, n=300, dim=2, spacing=0.01, jitter=0.3):
    """A jittered lattice-like cloud with per-particle fields of water-like magnitude."""
    side = int(np.ceil(n ** (1.0 / dim)))
    g = np.arange(side) * spacing
    x = np.stack(np.meshgrid(*([g] * dim), indexing="ij"), axis=-1).reshape(-1, dim)[:n]
    x = x + rng.uniform(-jitter, jitter, x.shape) * spacing
    n = x.shape[0]
    fields = dict(
        density=1000.0 * (1 + 0.02 * rng.standard_normal(n)),
        sound_speed=20.0 * (1 + 0.1 * rng.random(n)),
        masses=1000.0 * spacing**dim * (1 + 0.05 * rng.random(n)),
        h=1.3 * spacing * (1 + 0.1 * rng.random(n)),
    )
    table = find_neighbors(x, x, radius=2.0 * fields["h"].max() * 1.01)
    return x, fields, table


def _force(x, v, fields, table, reference=False, **kw):
    fn = monaghan_viscosity_force_reference if reference else monaghan_viscosity_force
    f = fields
    return fn(x, v, f["density"], f["sound_speed"], f["masses"], f["h"], table, **kw)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize(
    "kernel,alpha,beta",
    [("cubic_spline", 0.05, 0.0), ("wendland_c2", 1.0, 1.0), ("quintic_spline", 0.1, 0.5)],
)
def test_numba_matches_reference(rng, dim, kernel, alpha, beta):
    x, fields, table = _cloud(rng, dim=dim)
    if kernel == "quintic_spline":  # support 3 h
        table = find_neighbors(x, x, radius=3.0 * fields["h"].max() * 1.01)
    v = rng.standard_normal(x.shape)
    active = rng.random(x.shape[0]) < 0.7
    for act in (None, active):
        f, phi = _force(x, v, fields, table, kernel=kernel, alpha=alpha, beta=beta, active=act)
        fr, phir = _force(
            x, v, fields, table, reference=True, kernel=kernel, alpha=alpha, beta=beta, active=act
        )
        scale = np.abs(fr).max()
        assert scale > 0
        np.testing.assert_allclose(f, fr, rtol=1e-11, atol=1e-12 * scale)
        assert phi == pytest.approx(phir, rel=1e-13)
        if act is not None:
            assert not f[~act].any()
            full, _ = _force(x, v, fields, table, kernel=kernel, alpha=alpha, beta=beta)
            np.testing.assert_array_equal(f[act], full[act])


@pytest.mark.parametrize("dim", [2, 3])
def test_linear_and_angular_momentum_conserved(rng, dim):
    x, fields, table = _cloud(rng, dim=dim)
    v = rng.standard_normal(x.shape)
    f, _ = _force(x, v, fields, table, alpha=1.0, beta=1.0)
    scale = np.abs(f).sum()
    assert np.abs(f.sum(axis=0)).max() < 1e-13 * scale
    xc = x - x.mean(axis=0)
    torque = np.cross(xc, f) if dim == 3 else xc[:, 0] * f[:, 1] - xc[:, 1] * f[:, 0]
    lever = np.abs(xc).max()
    assert np.abs(torque.sum(axis=0)).max() < 1e-12 * lever * scale


def test_pair_forces_antisymmetric_bitwise(rng):
    x = rng.random((2, 3)) * 0.01
    v = rng.standard_normal((2, 3))
    v[1] = v[0] + (x[0] - x[1]) * 50  # v_01 = -50 x_01: approaching
    table = find_neighbors(x, x, radius=1.0)
    f, _ = monaghan_viscosity_force(
        x, v, [1000.0, 990.0], [20.0, 21.0], [1e-3, 2e-3], [0.01, 0.012], table, alpha=1.0, beta=1.0
    )
    assert np.abs(f).max() > 0
    np.testing.assert_array_equal(f[0], -f[1])
    d = x[0] - x[1]  # central: parallel to x_ij
    assert np.linalg.norm(np.cross(f[0], d)) < 1e-12 * np.linalg.norm(f[0]) * np.linalg.norm(d)


def test_rigid_translation_gives_zero(rng):
    x, fields, table = _cloud(rng)
    v = np.broadcast_to([3.0, -1.5], x.shape)
    f, phi = _force(x, v, fields, table, alpha=1.0, beta=1.0)
    assert not f.any() and phi == 0.0


def test_expansion_gives_zero_but_phi_counts(rng):
    x, fields, table = _cloud(rng)
    v = 2.0 * (x - x.mean(axis=0))  # v_ij . x_ij = 2 r^2 > 0
    f, phi = _force(x, v, fields, table, alpha=1.0, beta=1.0)
    assert not f.any()
    assert phi > 0  # separating pairs still enter max |phi| (conservative time step)
    f_c, _ = _force(x, -v, fields, table, alpha=1.0, beta=1.0)  # compression
    assert np.abs(f_c).max() > 0
    # compression: forces push particles outward (decelerate the inflow): f . (x - xc) >= 0 overall
    assert np.sum(f_c * (x - x.mean(axis=0))) > 0


def test_rigid_rotation_gives_negligible_force(rng):
    x, fields, table = _cloud(rng)
    xc = x - x.mean(axis=0)
    v = 5.0 * np.stack([-xc[:, 1], xc[:, 0]], axis=1)  # v_ij . x_ij = 0 up to round-off
    f, _ = _force(x, v, fields, table, alpha=1.0, beta=1.0)
    v_rand = rng.standard_normal(x.shape) * np.abs(v).max()
    f_rand, _ = _force(x, v_rand, fields, table, alpha=1.0, beta=1.0)
    assert np.abs(f).max() < 1e-12 * np.abs(f_rand).max()


@pytest.mark.parametrize("seed", range(3))
def test_dissipative(seed):
    rng = np.random.default_rng(seed)
    x, fields, table = _cloud(rng, dim=2)
    v = rng.standard_normal(x.shape)
    f, _ = _force(x, v, fields, table, alpha=0.5, beta=0.5)
    power = np.sum(f * v)
    assert power < 0
    # per pair: Σ_i f_i . v_i = Σ_pairs f_ij . v_ij / 2 <= 0 holds for every pair term, so also
    # for the quadratic-only viscosity
    f_b, _ = _force(x, v, fields, table, alpha=0.0, beta=1.0)
    assert np.sum(f_b * v) <= 0


def test_head_on_pair_against_hand_formula():
    x = np.array([[0.0, 0.0], [0.01, 0.0]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0]])
    rho, c = np.array([1000.0, 1010.0]), np.array([20.0, 22.0])
    m, h = np.array([0.1, 0.12]), np.array([0.012, 0.013])
    alpha, beta = 0.3, 0.7
    table = find_neighbors(x, x, radius=0.05)
    f, max_phi = monaghan_viscosity_force(x, v, rho, c, m, h, table, alpha=alpha, beta=beta)
    hij, r = 0.0125, 0.01
    phi = hij * (2.0 * -0.01) / (r**2 + 0.01 * hij**2)
    pi = (-alpha * 21.0 * phi + beta * phi**2) / 1005.0
    dwdr = get_kernel("cubic_spline").derivative(r, hij, 2)
    fx0 = -0.1 * 0.12 * pi * dwdr * (-0.01) / r
    assert max_phi == pytest.approx(abs(phi), rel=1e-14)
    np.testing.assert_allclose(f, [[fx0, 0.0], [-fx0, 0.0]], rtol=1e-13)
    assert fx0 < 0  # i moves in +x: pushed back


def test_pairs_beyond_support_ignored():
    x = np.array([[0.0], [0.025]])  # r = 2.08 h for h = 0.012 (cubic spline support 2 h)
    v = np.array([[1.0], [-1.0]])
    table = find_neighbors(x, x, radius=1.0)
    f, phi = monaghan_viscosity_force(x, v, 1000.0, 20.0, 0.1, 0.012, table, alpha=1.0, beta=1.0)
    assert not f.any() and phi == 0.0


def test_bad_input(rng):
    x, fields, table = _cloud(rng, n=25)
    v = np.zeros_like(x)
    with pytest.raises(ValueError, match="velocity"):
        _force(x, v[:, :1], fields, table)
    with pytest.raises(ValueError, match="density"):
        _force(x, v, fields | dict(density=-fields["density"]), table)
    with pytest.raises(ValueError, match="h must"):
        _force(x, v, fields | dict(h=fields["h"][:-1]), table)
    with pytest.raises(ValueError, match="themselves"):
        _force(x, v, fields, find_neighbors(x[:5], x, radius=0.03))
    with pytest.raises(ValueError, match="alpha and beta"):
        _force(x, v, fields, table, alpha=-0.1)
    with pytest.raises(ValueError, match="active"):
        _force(x, v, fields, table, active=np.arange(x.shape[0]))
    with pytest.raises(ValueError, match="unknown kernel"):
        _force(x, v, fields, table, kernel="nope")
    with pytest.raises(ValueError, match="not finite"):
        _force(x, np.full_like(x, np.nan), fields, table)
