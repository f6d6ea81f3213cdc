"""Density diffusion, particle shifting and the corrected density gradient
(:mod:`mlsgalerkin.fluid.density_diffusion`, :mod:`mlsgalerkin.fluid.shifting`,
:mod:`mlsgalerkin.fluid.corrected_gradient`): numba kernels against their numpy references,
the exactness and conservation each formula promises, and the effects in small scenes
(hydrostatic rest, bit-identical restart, clear errors).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.fluid import (
    DensityDiffusion,
    FluidBody,
    FreeSurfaceDetection,
    Gravity,
    MonaghanViscosity,
    ParticleShifting,
    Phase,
    TaitEOS,
    TaitPressure,
    Walls,
    density_diffusion_limit,
    lattice,
    wall_box,
)
from mlsgalerkin.fluid.corrected_gradient import ratio_gradient, ratio_gradient_reference
from mlsgalerkin.fluid.density_diffusion import (
    density_diffusion_rate,
    density_diffusion_rate_reference,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.fluid.shifting import shift_vectors, shift_vectors_reference
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.scene import Output, Scene
from mlsgalerkin.simulation import Simulation

KERNEL = get_kernel("cubic_spline")
DX = 0.01
H = 1.3 * DX
G = 9.81



def _scheme_options(kw: dict) -> dict:
    """Take the fluid scheme's options (approximation, integrator, mass, safety, dt_max) out of ``kw``."""
    return {k: kw.pop(k) for k in ("approximation", "integrator", "mass", "safety", "dt_max") if k in kw}

def cloud(nx=12, ny=10, jitter=0.0, seed=0, walls=False):
    """A block of fluid particles (``nx × ny``, spacing DX; a free surface on every side unless
    ``walls``, then a 3-layer floor below) with uniform h, unit-ish volumes and a CSR table."""
    rng = np.random.default_rng(seed)
    x = lattice((0.0, 0.0), (nx * DX, ny * DX), DX)
    x = x + jitter * DX * rng.uniform(-1, 1, x.shape)
    n_fluid = len(x)
    if walls:
        floor = lattice((-3 * DX, -3 * DX), ((nx + 3) * DX, 0.0), DX)
        x = np.vstack([x, floor])
    n = len(x)
    h = np.full(n, H)
    M = np.full(n, 1000.0 * DX * DX)
    rho = np.full(n, 1000.0)
    rho0 = np.full(n, 1000.0)
    phase = np.zeros(n, dtype=np.int64)
    nb = find_neighbors(x, x, KERNEL.support * H)
    return x, h, M, rho, rho0, phase, nb, n_fluid


# ------------------------------------------------------------------- corrected gradient
@settings(max_examples=15, deadline=None)
@given(jitter=st.floats(0.0, 0.3), seed=st.integers(0, 10_000))
def test_ratio_gradient_matches_reference_and_is_linearly_exact(jitter, seed):
    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=jitter, seed=seed)
    a = np.array([0.7, -1.9])
    rho = rho0 * (1.0 + 0.01 * (x @ a))                     # a linear ratio field
    vol = M / rho
    g, ok = ratio_gradient(x, rho / rho0, vol, h, phase, nb.indptr, nb.indices, nf, KERNEL)
    gr, okr = ratio_gradient_reference(x, rho / rho0, vol, h, phase, nb.indptr, nb.indices, nf, KERNEL)
    np.testing.assert_array_equal(ok, okr)
    np.testing.assert_allclose(g, gr, rtol=1e-10, atol=1e-12)
    assert ok.sum() > 0.5 * nf                               # the interior and most of the surface
    np.testing.assert_allclose(g[ok], np.broadcast_to(0.01 * a, g[ok].shape), rtol=1e-9, atol=1e-12)


def test_ratio_gradient_ignores_other_phases_and_walls():
    x, h, M, rho, rho0, phase, nb, nf = cloud(walls=True)
    rho[nf:] = 5000.0                                         # wall rows: never partners
    phase[: nf // 2] = 1                                      # two phases, a jump in ratio between them
    rho0[: nf // 2] = 1030.0
    rho[:nf] = rho0[:nf]
    g, ok = ratio_gradient(x, rho / rho0, M / rho, h, phase, nb.indptr, nb.indices, nf, KERNEL)
    assert np.abs(g).max() < 1e-12


# ------------------------------------------------------------------- density diffusion
@pytest.mark.parametrize("correction", ["gradient", "hydrostatic", "none"])
def test_density_diffusion_matches_reference(correction):
    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=0.2, seed=3, walls=True)
    rng = np.random.default_rng(1)
    rho[:nf] *= 1.0 + 0.01 * rng.standard_normal(nf)
    args = (x, rho, rho0, M, h, phase, nb.indptr, nb.indices, nf, KERNEL, 0.1, 20.0, correction,
            np.array([0.0, -G]))
    fast = density_diffusion_rate(*args)
    ref = density_diffusion_rate_reference(*args)
    np.testing.assert_allclose(fast, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


@pytest.mark.parametrize("correction", ["gradient", "none"])
def test_density_diffusion_moves_density_not_mass(correction):
    """Σ V_i ρ̇_i / ρ0_i = 0 for a uniform h: the flux is antisymmetric (module docstring)."""
    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=0.25, seed=5)
    rng = np.random.default_rng(2)
    rho = rho * (1.0 + 0.02 * rng.standard_normal(len(rho)))
    rate = density_diffusion_rate(x, rho, rho0, M, h, phase, nb.indptr, nb.indices, nf, KERNEL, 0.1, 20.0,
                                  correction)
    vol = M / rho
    assert abs(np.sum(vol[:nf] * rate / rho0[:nf])) < 1e-10 * np.sum(vol[:nf] * np.abs(rate) / rho0[:nf])
    assert np.abs(rate).max() > 1.0                         # it does act on the noise


def test_density_diffusion_leaves_hydrostatic_and_linear_fields_alone():
    """A fluid at hydrostatic rest: ``none`` diffuses the hydrostatic gradient, ``hydrostatic``
    and ``gradient`` give (almost) nothing — also at the free surface."""
    c0 = 20.0
    x, h, M, rho, rho0, phase, nb, nf = cloud(nx=10, ny=16)
    eos = TaitEOS(1000.0, c0)
    top = x[:nf, 1].max() + 0.5 * DX
    rho[:nf] = eos.density(1000.0 * G * (top - x[:nf, 1]))
    rates = {c: density_diffusion_rate(x, rho, rho0, M, h, phase, nb.indptr, nb.indices, nf, KERNEL, 0.1, c0, c,
                                       np.array([0.0, -G]))
             for c in ("none", "hydrostatic", "gradient")}
    none = np.abs(rates["none"]).max()
    assert none > 1.0                                         # kg/m³/s: the surface rows lose density
    # Fourtakas et al.'s difference (1 + γ g·x_ji/c0²)^(1/γ) − 1 is exact at the surface only; at
    # depth d it misses the cross term (γ − 1)(g d/c0²) of the Tait curve: here 0.016 · 6 ≈ 2.4 %
    assert np.abs(rates["hydrostatic"]).max() < 0.05 * none
    assert np.abs(rates["hydrostatic"][-12:]).max() < 1e-3 * none      # the top row: exact
    assert np.abs(rates["gradient"]).max() < 1e-3 * none


def test_density_diffusion_limit():
    assert density_diffusion_limit(np.array([0.02, 0.01]), 0.1, 10.0) == pytest.approx(0.125 * 0.01 / 1.0)


# ------------------------------------------------------------------- shifting
@settings(max_examples=15, deadline=None)
@given(jitter=st.floats(0.0, 0.3), seed=st.integers(0, 10_000), walls=st.booleans())
def test_shift_matches_reference(jitter, seed, walls):
    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=jitter, seed=seed, walls=walls)
    args = (x, M / rho, h, nb.indptr, nb.indices, nf, KERNEL, DX, 2.0, 1e-4)
    d, lam, kind = shift_vectors(*args)
    dr, lamr, kindr = shift_vectors_reference(*args)
    np.testing.assert_allclose(lam, lamr, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(kind, kindr)
    np.testing.assert_allclose(d, dr, rtol=1e-8, atol=1e-15)


def test_shift_pushes_a_displaced_particle_back_and_spares_the_lattice():
    x, h, M, rho, rho0, phase, nb, nf = cloud(nx=15, ny=15, walls=True)
    centre = int(np.argmin(np.linalg.norm(x[:nf] - x[:nf].mean(axis=0), axis=1)))
    site = x[centre].copy()
    x[centre] += np.array([0.3, 0.2]) * DX
    nb = find_neighbors(x, x, KERNEL.support * H)
    d, lam, kind = shift_vectors(x, M / rho, h, nb.indptr, nb.indices, nf, KERNEL, DX, 2.0, 1e-4)
    back = site - x[centre]
    assert d[centre] @ back > 0.8 * np.linalg.norm(d[centre]) * np.linalg.norm(back)   # towards its site
    assert kind[centre] == 0 and lam[centre] > 0.9
    far = np.linalg.norm(x[:nf] - site, axis=1) > 2.5 * H                # untouched lattice interior
    interior = far & (lam > 0.9)
    assert interior.sum() > 20
    assert np.abs(d[interior]).max() < 1e-6 * np.abs(d[centre]).max()


def test_shift_never_lifts_the_free_surface_and_spares_splashes():
    x, h, M, rho, rho0, phase, nb, nf = cloud(nx=14, ny=8, jitter=0.2, seed=7, walls=True)
    drop = np.array([[0.5, 0.5]])                              # far away: a lone splash
    x = np.vstack([x[:nf], drop, x[nf:]])
    nf += 1
    M = np.append(M, M[0])
    rho = np.append(rho, 1000.0)
    h = np.append(h, H)
    nb = find_neighbors(x, x, KERNEL.support * H)
    d, lam, kind = shift_vectors(x, M / rho, h, nb.indptr, nb.indices, nf, KERNEL, DX, 2.0, 1e-4)
    assert kind[nf - 1] == 2 and np.all(d[nf - 1] == 0.0)
    top = x[:nf - 1, 1] > x[:nf - 1, 1].max() - 0.6 * DX     # the top row: surface particles
    assert np.all(kind[:nf - 1][top] % 3 != 0)                # surface (1), or a corner left alone (2)
    assert np.sum(kind[:nf - 1][top] % 3 == 1) > 8
    # with the normal component removed, the top row is not lifted off the surface (jitter only
    # tilts the estimated normal a little)
    assert np.abs(d[:nf - 1][top, 1]).max() < 0.3 * np.abs(d[:nf - 1][top, 0]).max()


# ------------------------------------------------------------------- in scenes
def tank(effects, dx=0.02, depth=0.3, width=0.3, t_end=0.2, **kw) -> Scene:
    c0 = 10.0 * math.sqrt(2.0 * G * depth)
    eos = TaitEOS(1000.0, c0)
    water = FluidBody.block("water", (0.0, 0.0), (width, depth), dx, [Phase("water", 1000.0)])
    water.density[:] = eos.density(1000.0 * G * (depth - water.positions[:, 1]))
    walls = wall_box((0.0, 0.0), (width, 2.0 * depth), dx, layers=3)   # rows on the lattice
    listed = [TaitPressure(c0), Gravity(), Walls("free_slip"), MonaghanViscosity(0.02)] + list(effects)
    return Scene([water, walls], [FluidScheme(listed, **_scheme_options(kw), stabilisation="as_listed")], t_end=t_end, name="tank", **kw)


def test_tank_with_diffusion_and_shifting_stays_at_rest():
    res = Simulation(tank([DensityDiffusion(), ParticleShifting()])).run(out=None, progress=False)
    s = res.state.fluid
    f = s.fluid
    speed = np.linalg.norm(s.v[f], axis=1).max()
    assert speed < 0.02 * math.sqrt(G * 0.3)                  # spurious speed: 2 % of the wave speed
    assert np.isfinite(s.rho[f]).all()
    reports = res.summary["fluid"]["effect_reports"]
    assert reports["particle_shifting"]["steps"] == res.summary["steps"] // 4      # every 4th drift
    assert 0 < reports["particle_shifting"]["largest_shift_per_step_dx"] <= 0.1


@pytest.mark.parametrize("integrator", ["kdk", "predictor_corrector"])
def test_restart_with_diffusion_and_shifting_is_bit_identical(tmp_path, integrator):
    def scene():
        return tank([DensityDiffusion(), ParticleShifting()], t_end=0.04, integrator=integrator,
                    output=Output(checkpoint_every=0.01))

    ref = Simulation(scene()).run(out=tmp_path / "ref", progress=False)
    part = Simulation(scene()).run(out=tmp_path / "run", progress=False, max_steps=23)
    assert part.state.step == 23
    res = Simulation(scene()).run(out=tmp_path / "run", restart="latest", progress=False)
    for k in ("x", "v", "rho", "p"):
        assert np.array_equal(getattr(ref.state.fluid, k), getattr(res.state.fluid, k)), k
    assert ref.summary["fluid"]["effect_reports"] == res.summary["fluid"]["effect_reports"]


def test_bad_stabilisation_parameters_are_reported_before_work():
    from mlsgalerkin.scene import SceneError

    for effect, words in [(DensityDiffusion(delta=-1.0), "delta"),
                          (DensityDiffusion(correction="upwind"), "correction"),
                          (ParticleShifting(splash=0.95), "splash"),
                          (ParticleShifting(max_shift=0.0), "max_shift")]:
        with pytest.raises(SceneError, match=words):
            Simulation(tank([effect]))
    sc = tank([])
    next(e for e in sc.effects if isinstance(e, TaitPressure)).negative_pressure = "free_surface"
    with pytest.raises(SceneError, match="FreeSurfaceDetection"):
        Simulation(sc)
    sc = tank([FreeSurfaceDetection(every=5)])
    next(e for e in sc.effects if isinstance(e, TaitPressure)).negative_pressure = "free_surface"
    Simulation(sc)                                            # accepted with the detection listed


# ------------------------------------------------------------------- MLS pressure gradient
def _table(x, h, nb):
    from mlsgalerkin.approximation.build import evaluate_shape_functions

    return evaluate_shape_functions(x, x, h, nb, KERNEL, 1, "mls", None)


def test_scalar_gradient_matches_reference():
    from mlsgalerkin.assembly import scalar_gradient, scalar_gradient_reference

    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=0.2, seed=11, walls=True)
    table = _table(x, h, nb)
    f = np.random.default_rng(4).standard_normal(len(x))
    np.testing.assert_allclose(scalar_gradient(table, f, nf), scalar_gradient_reference(table, f, nf), rtol=1e-12,
                               atol=1e-9)


def test_mls_ratio_gradient_is_exact_for_hydrostatic_two_layers_and_walls():
    """Two layers (1000 over 1030 kg/m³) at hydrostatic rest on a wall floor whose particles
    carry the extrapolated pressure: the ratio gradient from the MLS pressure gradient is the
    exact one, ρ0 g/(ρ0 c²) per phase, at the surface, the interface and the floor."""
    from mlsgalerkin.fluid.corrected_gradient import ratio_gradient_mls

    c0, gamma = 20.0, 7.0
    x, h, M, rho, rho0, phase, nb, nf = cloud(nx=10, ny=16, walls=True)
    top = x[:nf, 1].max() + 0.5 * DX
    half = 0.5 * top
    y = x[:, 1]
    p = np.where(y > half, 1000.0 * G * (top - y), 1000.0 * G * (top - half) + 1030.0 * G * (half - y))
    rho0[:] = np.where(y > half, 1000.0, 1030.0)
    phase[:] = (y <= half).astype(np.int64)
    rho[:] = rho0 * (1.0 + gamma * p / (rho0 * c0 * c0)) ** (1.0 / gamma)
    table = _table(x, h, nb)
    grad = ratio_gradient_mls(table, rho, rho0, p, nf, c0, gamma)
    r = rho[:nf] / rho0[:nf]
    exact = -G / (c0 * c0 * r ** (gamma - 1.0))       # dr/dy = (dp/dy)/(dp/dr), dp/dy = −ρ0 g here
    # MLS is linear-exact; p has a kink at the interface, so the rows within a support of it see
    # a mix of the two slopes
    far = np.abs(x[:nf, 1] - half) > KERNEL.support * H
    np.testing.assert_allclose(grad[far, 0], 0.0, atol=1e-9)
    assert np.abs(grad[~far, 0]).max() < 1e-3 * np.abs(exact).max()
    np.testing.assert_allclose(grad[far, 1], exact[far], rtol=1e-8)
    assert np.all(np.abs(grad[~far, 1] / exact[~far] - 1.0) < 0.04)


# ------------------------------------------------------------------- residual pair viscosity
def test_residual_monaghan_matches_reference_and_spares_linear_flows():
    """``residual=True`` damps only the deviation of the pair velocity from the linear field
    ``½(L_i + L_j) x_ij``: no force in a uniformly compressing flow, the same numba/numpy
    result as the plain form otherwise."""
    from mlsgalerkin.fluid.pair_viscosity import (
        monaghan_viscosity_force,
        monaghan_viscosity_force_reference,
    )

    x, h, M, rho, rho0, phase, nb, nf = cloud(jitter=0.15, seed=2)
    A = np.array([[-3.0, 1.0], [0.5, -2.0]])                  # a compressing linear flow (1/s)
    v = x @ A.T
    L = np.broadcast_to(A, (len(x), 2, 2)).copy()
    c = np.full(len(x), 20.0)
    plain, _ = monaghan_viscosity_force(x, v, rho, c, M, h, nb, "cubic_spline", 0.1)
    resid, _ = monaghan_viscosity_force(x, v, rho, c, M, h, nb, "cubic_spline", 0.1, gradient=L)
    assert np.abs(plain).max() > 1e-3
    assert np.abs(resid).max() < 1e-12 * np.abs(plain).max()
    noisy = v + 0.05 * np.random.default_rng(3).standard_normal(v.shape)
    fast, _ = monaghan_viscosity_force(x, noisy, rho, c, M, h, nb, "cubic_spline", 0.1, gradient=L)
    ref, _ = monaghan_viscosity_force_reference(x, noisy, rho, c, M, h, nb, "cubic_spline", 0.1, gradient=L)
    np.testing.assert_allclose(fast, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
    assert np.abs(fast).max() > 1e-4
