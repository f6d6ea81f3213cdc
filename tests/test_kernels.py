"""Kernel (window) functions: normalisation, derivatives, support, smoothness, registry.

Every kernel is ``W(r, h) = alpha_d / h**d * f(q)``, ``q = r / h`` (see ``mlsgalerkin.kernels``).
Reference values are the corrected constants of Xing (2019) and Liu & Liu (2003).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import gamma, gammainc

from mlsgalerkin.kernels import KERNELS, Kernel, get_kernel, kernel_f_df, kernel_names

PI = math.pi
NAMES = list(KERNELS)
DIMS = (1, 2, 3)
#: Surface of the unit sphere in d dimensions (the 1D "sphere" is the two points ±1).
SURFACE = {1: 2.0, 2: 2.0 * PI, 3: 4.0 * PI}
#: All break points of the piecewise kernels; quadrature and finite differences avoid them.
BREAKS = (0.5, 1.0, 1.5, 2.0, 2.5)
#: Interior joins of the piecewise-polynomial splines.
JOINS = {"cubic_spline": (1.0,), "quartic_spline": (0.5, 1.5), "quintic_spline": (1.0, 2.0)}

#: Support (in units of h) and constants (alpha_1, alpha_2, alpha_3), hard-coded from the corrected
#: table of Xing (2019) and Liu & Liu (2003) (corrections: Lucy 3D carries pi, quintic 3D is exactly
#: 1/(120 pi)) and, for Wendland, the Dehnen & Aly (2012) values with support q < 2.
EXPECTED = {
    "quadratic": (1.0, (3 / 4, 2 / PI, 15 / (8 * PI))),
    "lucy_quartic": (1.0, (5 / 4, 5 / PI, 105 / (16 * PI))),
    "johnson_quadratic": (2.0, (1.0, 2 / PI, 5 / (4 * PI))),
    "gaussian": (3.0, (1 / math.sqrt(PI), 1 / PI, 1 / PI**1.5)),
    "super_gaussian": (2.0, (1 / math.sqrt(PI), 1 / PI, 1 / PI**1.5)),
    "cubic_spline": (2.0, (2 / 3, 10 / (7 * PI), 1 / PI)),
    "quartic_spline": (2.5, (1 / 24, 96 / (1199 * PI), 1 / (20 * PI))),
    "quintic_spline": (3.0, (1 / 120, 7 / (478 * PI), 1 / (120 * PI))),
    "new_quartic": (2.0, (1.0, 15 / (7 * PI), 315 / (208 * PI))),
    "wendland_c2": (2.0, (5 / 8, 7 / (4 * PI), 21 / (16 * PI))),
    "wendland_c4": (2.0, (3 / 4, 9 / (4 * PI), 495 / (256 * PI))),
}


@pytest.fixture(params=NAMES)
def kernel(request) -> Kernel:
    return KERNELS[request.param]


@pytest.fixture(params=DIMS)
def dim(request) -> int:
    return request.param


def _integral(k: Kernel, d: int) -> float:
    """∫ W dV over the support with h = 1: S_d * alpha_d * ∫_0^support f(q) q^(d-1) dq."""
    pts = [b for b in BREAKS if b < k.support]
    val, err = quad(
        lambda q: float(k.shape(q, d)) * q ** (d - 1),
        0.0,
        k.support,
        points=pts or None,
        epsabs=1e-14,
        epsrel=1e-13,
        limit=200,
    )
    assert err < 1e-12
    return SURFACE[d] * k.normalisation(d) * val


def _scales(k: Kernel, d: int) -> tuple[float, float]:
    """max |f| and max |f'| over the support (at least 1): magnitudes for absolute tolerances."""
    q = np.linspace(0.0, k.support, 20001)[:-1]
    return (
        max(1.0, float(np.abs(k.shape(q, d)).max())),
        max(1.0, float(np.abs(k.shape_derivative(q, d)).max())),
    )


def _order(k: Kernel) -> int:
    """Claimed continuity order from the ``smoothness`` string ("C2" -> 2); -1 if none given."""
    s = k.smoothness
    return int(s[1]) if len(s) > 1 and s[0] == "C" and s[1].isdigit() else -1


def _nb(k: Kernel, q: float, d: int) -> tuple[float, float]:
    return kernel_f_df(k.kernel_id, float(q), k.support, d)


# --------------------------------------------------------------------------------------
# normalisation
# --------------------------------------------------------------------------------------


TRUNCATED = ("gaussian", "super_gaussian")


def test_exact_unity_flags():
    assert {n for n, k in KERNELS.items() if not k.exact_unity} == set(TRUNCATED)


@pytest.mark.parametrize("name", [n for n in NAMES if n not in TRUNCATED])
def test_unity(name, dim):
    """∫ W dV = 1 over the support (the truncated Gaussians: test_truncated_gaussian_family)."""
    assert abs(_integral(KERNELS[name], dim) - 1.0) < 1e-10


def _truncated_mass(name: str, d: int) -> float:
    r"""Closed-form ``∫_{|x| < R} W dV`` of the truncated Gaussian family.

    With ``s = d/2`` and ``|S^{d-1}| = 2 pi^s / Gamma(s)``, substituting ``t = q^2``:

    * Gaussian, ``W = pi^-s e^{-q^2}``, ``R = 3``:
      ``2/Gamma(s) * ∫_0^3 q^(d-1) e^{-q^2} dq = gamma(s, 9) / Gamma(s) = gammainc(d/2, 9)``.
    * Super-Gaussian, ``W = pi^-s (s + 1 - q^2) e^{-q^2}``, ``R = 2``:
      ``[(s+1) gamma(s, 4) - gamma(s+1, 4)] / Gamma(s)``, and with
      ``gamma(s+1, x) = s gamma(s, x) - x^s e^{-x}`` this is
      ``gammainc(d/2, 4) + 4^(d/2) e^{-4} / Gamma(d/2)``.

    The constants ``alpha_d = pi^{-d/2}`` normalise the *untruncated* functions (both tend to 1 as
    R -> inf). Cutting the Gaussian at q = 3 drops its positive tail, so it integrates to slightly
    less than 1 (1 - 2.2e-5 in 1D ... 1 - 4.4e-4 in 3D). The super-Gaussian's tail beyond q = 2 is
    *negative* (s + 1 - q^2 < 0 there for d <= 3), so cutting it leaves an excess (1.016 in 1D ...
    1.119 in 3D).
    """
    s = d / 2.0
    if name == "gaussian":
        return float(gammainc(s, 9.0))
    if name == "super_gaussian":
        return float(gammainc(s, 4.0) + 4.0**s * math.exp(-4.0) / gamma(s))
    raise AssertionError(name)


@pytest.mark.parametrize("name", TRUNCATED)
def test_truncated_gaussian_family(name, dim):
    k = KERNELS[name]
    assert not k.exact_unity  # the flag must be honest: these do not integrate to one
    expected = _truncated_mass(name, dim)
    assert abs(_integral(k, dim) - expected) < 1e-10
    assert abs(expected - 1.0) > 1e-5  # the deficit/excess is real, not rounding

    r = k.renormalised()
    assert r.exact_unity
    assert abs(_integral(r, dim) - 1.0) < 1e-10
    # and the new constant is the old one divided by the closed-form mass
    assert r.normalisation(dim) == pytest.approx(k.normalisation(dim) / expected, rel=1e-12)


@pytest.mark.parametrize("support", [2.0, 3.0])
def test_gaussian_with_support(support, dim):
    """Xing (2019): the truncation at q = 2 loses ~0.5 % (1D) to ~5 % (3D) of the mass."""
    g = KERNELS["gaussian"].with_support(support)
    assert g.support == support
    mass = float(gammainc(dim / 2.0, support**2))
    assert abs(_integral(g, dim) - mass) < 1e-10
    if support == 2.0:
        assert {1: 0.9953, 2: 0.9817, 3: 0.9540}[dim] == pytest.approx(mass, abs=1e-4)
    assert abs(_integral(KERNELS["gaussian"].with_support(support, renormalise=True), dim) - 1) < 1e-10
    with pytest.raises(ValueError, match="support must be positive"):
        KERNELS["gaussian"].with_support(0.0)


def test_value_scales_with_h(kernel, dim, rng):
    """W(r, h) = W(r/h, 1) / h^d, so ∫W dV = 1 for every h."""
    h = 0.37
    r = rng.uniform(0.0, 1.2 * kernel.support * h, 50)
    np.testing.assert_allclose(
        kernel.value(r, h, dim), kernel.value(r / h, 1.0, dim) / h**dim, rtol=1e-13, atol=0
    )
    np.testing.assert_allclose(
        kernel.derivative(r, h, dim),
        kernel.normalisation(dim) / h ** (dim + 1) * kernel.shape_derivative(r / h, dim),
        rtol=1e-13,
        atol=0,
    )


# --------------------------------------------------------------------------------------
# derivative, support, continuity
# --------------------------------------------------------------------------------------


def test_derivative_matches_finite_difference(kernel, dim):
    step = 1e-6
    q = np.linspace(0.01, kernel.support - 0.01, 3001)
    q = q[np.min(np.abs(q[:, None] - np.array(BREAKS)[None, :]), axis=1) > 1e-3]
    fd = (kernel.shape(q + step, dim) - kernel.shape(q - step, dim)) / (2 * step)
    df = kernel.shape_derivative(q, dim)
    # relative 1e-6, plus an absolute floor for the roundoff of the difference quotient
    # (eps * |terms| / step, ~1e-9 of the kernel's scale) where df passes through zero
    _, dscale = _scales(kernel, dim)
    assert np.all(np.abs(fd - df) <= 1e-6 * np.abs(df) + 1e-8 * dscale)


def test_compact_support(kernel, dim):
    s = kernel.support
    q = np.concatenate([[s, np.nextafter(s, np.inf)], np.linspace(s, 5 * s, 101), [1e300, np.inf]])
    assert np.all(kernel.shape(q, dim) == 0.0)
    assert np.all(kernel.shape_derivative(q, dim) == 0.0)
    for x in q:
        assert _nb(kernel, x, dim) == (0.0, 0.0)
    assert np.all(kernel.value(q, 1.0, dim) == 0.0)
    # ... and it is not identically zero just inside
    assert kernel.shape(np.nextafter(s, 0.0) * 0.9, dim) != 0.0


def test_even(kernel, dim, rng):
    q = rng.uniform(0.0, 1.2 * kernel.support, 100)
    np.testing.assert_array_equal(kernel.shape(-q, dim), kernel.shape(q, dim))


@pytest.mark.parametrize("name", list(JOINS))
def test_continuity_at_joins(name, dim):
    """f and f' (and f'' for these >= C2 splines) are continuous at the interior piece joins,
    in both the numpy reference and the branchy numba version."""
    k = KERNELS[name]
    fscale, dscale = _scales(k, dim)
    for j in JOINS[name]:
        lo, hi = np.nextafter(j, 0.0), np.nextafter(j, np.inf)
        for f_lo, f_hi, scale in [
            (k.shape(lo, dim), k.shape(hi, dim), fscale),
            (k.shape_derivative(lo, dim), k.shape_derivative(hi, dim), dscale),
            (_nb(k, lo, dim)[0], _nb(k, hi, dim)[0], fscale),
            (_nb(k, lo, dim)[1], _nb(k, hi, dim)[1], dscale),
        ]:
            assert abs(f_lo - f_hi) <= 1e-13 * scale, (j, f_lo, f_hi)
        # one-sided second derivatives from f' agree (their gap is O(step * f''') ~ 1e-6)
        assert _order(k) >= 2
        st = 1e-6
        left = (k.shape_derivative(j, dim) - k.shape_derivative(j - st, dim)) / st
        right = (k.shape_derivative(j + st, dim) - k.shape_derivative(j, dim)) / st
        assert abs(left - right) < 1e-4 * dscale, (j, left, right)


def test_smoothness_at_support_edge(kernel, dim):
    """Left limits at q = support: f -> 0 unless truncated; f' -> 0 where the kernel claims C1+."""
    s = kernel.support
    inside = np.nextafter(s, 0.0)
    f, df = float(kernel.shape(inside, dim)), float(kernel.shape_derivative(inside, dim))
    nf, ndf = _nb(kernel, inside, dim)
    order = _order(kernel)
    if kernel.name in ("gaussian", "super_gaussian"):
        assert order == -1 and abs(f) > 1e-5  # C∞ inside, but a genuine jump at the truncation
        return
    assert abs(f) < 1e-12 and abs(nf) < 1e-12  # every polynomial kernel is at least C0
    if kernel.smoothness.startswith(("C1", "C2", "C3", "C4")):
        assert abs(df) < 1e-12 and abs(ndf) < 1e-12
        # f'' from the inside: -> 0 for C2+, and the advertised non-zero value for C1
        st = 1e-6
        d2 = (kernel.shape_derivative(s - st, dim) - kernel.shape_derivative(s - 2 * st, dim)) / st
        if order >= 2:
            assert abs(d2) < 1e-4
        else:
            assert kernel.name == "new_quartic"
            assert d2 == pytest.approx(-0.25, abs=1e-4)  # f''(2) = -9/4 + 19/2 - 15/2
    if kernel.name == "quadratic":
        assert kernel.smoothness.startswith("C0")
        assert df == pytest.approx(-2.0) and ndf == pytest.approx(-2.0)  # W'(R=1) != 0


def test_slope_at_origin(kernel, dim):
    """∇W = 0 at r = 0 (f'(0) = 0) except for Johnson's kernel, which has a cusp there."""
    expected = -0.75 if kernel.name == "johnson_quadratic" else 0.0
    assert kernel.shape_derivative(0.0, dim) == pytest.approx(expected, abs=1e-12)
    assert _nb(kernel, 0.0, dim)[1] == pytest.approx(expected, abs=1e-12)


def test_numba_matches_numpy(kernel, dim, rng):
    """The compiled scalar dispatch reproduces the numpy reference.

    Tolerance 1e-13 relative to the kernel's magnitude (max |f|, max |f'|, at least 1): the
    quintic spline sums terms up to 3^5 = 243 that cancel to O(1), so evaluation-order rounding
    alone is ~1e-13 in absolute terms (~3e-15 of its scale).
    """
    q = rng.uniform(0.0, 1.1 * kernel.support, 2000)
    out = np.array([_nb(kernel, x, dim) for x in q])
    fscale, dscale = _scales(kernel, dim)
    assert np.max(np.abs(out[:, 0] - kernel.shape(q, dim))) <= 1e-13 * fscale
    assert np.max(np.abs(out[:, 1] - kernel.shape_derivative(q, dim))) <= 1e-13 * dscale


def test_nonnegative_flag(kernel, dim):
    q = np.linspace(0.0, kernel.support, 200_001)[:-1]
    f = kernel.shape(q, dim)
    assert (f.min() >= 0.0) == kernel.nonnegative, f.min()
    if kernel.nonnegative:
        # the "decay" property: nonnegative kernels never increase with distance
        assert np.all(kernel.shape_derivative(q, dim) <= 0.0)
    if kernel.name == "new_quartic":
        # documented dip: >= -0.24 % of f(0) (exactly -0.2375 %, at q = 1.8 where f' = 0), for
        # q beyond the simple root (16 + sqrt(1216)) / 30 = 1.69570... of
        # f = -(5/32) (q - 2)^2 (q^2 - 16/15 q - 16/15); the smoothness string rounds it to 1.696
        assert f.min() >= -0.0024 * f[0]
        assert f.min() == pytest.approx(-0.002375 * f[0], rel=1e-6)
        neg = q[f < 0]
        assert 1.6957 < neg.min() < 1.6958 and neg.max() > 1.9999


# --------------------------------------------------------------------------------------
# registry and constants
# --------------------------------------------------------------------------------------


def test_registry_matches_the_corrected_table():
    assert set(KERNELS) == set(EXPECTED)
    assert kernel_names() == list(KERNELS)
    assert len({k.kernel_id for k in KERNELS.values()}) == len(KERNELS)
    for name, (support, alpha) in EXPECTED.items():
        k = KERNELS[name]
        assert k.name == name
        assert k.support == support, name
        for d in DIMS:
            assert k.normalisation(d) == pytest.approx(alpha[d - 1], rel=1e-14), (name, d)


def test_cubic_spline_value_at_origin():
    k = get_kernel("cubic_spline")
    assert float(k.value(0.0, h=1.0, dim=2)) == pytest.approx(10 / (7 * PI), rel=1e-15)
    assert float(k.value(0.0, h=2.0, dim=3)) == pytest.approx(1 / PI / 8, rel=1e-15)


def test_get_kernel():
    k = KERNELS["wendland_c2"]
    assert get_kernel("wendland_c2") is k
    assert get_kernel(k) is k
    with pytest.raises(ValueError, match="unknown kernel 'nope'") as info:
        get_kernel("nope")
    for name in KERNELS:
        assert name in str(info.value)
    with pytest.raises(ValueError, match="unknown kernel"):
        get_kernel(None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="dim must be 1, 2 or 3"):
        k.normalisation(4)


# --------------------------------------------------------------------------------------
# value / gradient
# --------------------------------------------------------------------------------------


def test_value_shapes(kernel):
    r = np.linspace(0.0, 3.0, 20).reshape(4, 5)
    assert kernel.value(r, 1.0, 2).shape == (4, 5)
    assert kernel.value(r, np.full((4, 5), 0.5), 3).shape == (4, 5)
    assert kernel.value(r, np.full(5, 0.5), 1).shape == (4, 5)
    assert np.ndim(kernel.value(0.3, 1.0, 2)) == 0


def test_gradient(kernel, dim, rng):
    h = 0.8
    n = 40
    # offsets with 0.05 < q < 0.95 support: away from the origin, the edge and (mostly) joins
    u = rng.normal(size=(n, dim))
    u /= np.linalg.norm(u, axis=1)[:, None]
    r = rng.uniform(0.05, 0.95, n) * kernel.support * h
    dx = u * r[:, None]
    g = kernel.gradient(dx, h)
    assert g.shape == (n, dim)

    # the chain rule: grad W = dW/dr * dx / r ...
    dwdr = kernel.derivative(r, h, dim)
    np.testing.assert_allclose(g, dwdr[:, None] * u, rtol=1e-12, atol=1e-15)
    # ... checked against central differences of W(|dx|) in position
    step = 1e-6
    fd = np.empty_like(dx)
    for a in range(dim):
        e = np.zeros(dim)
        e[a] = step
        fd[:, a] = (
            kernel.value(np.linalg.norm(dx + e, axis=1), h, dim)
            - kernel.value(np.linalg.norm(dx - e, axis=1), h, dim)
        ) / (2 * step)
    _, dscale = _scales(kernel, dim)
    scale = kernel.normalisation(dim) / h ** (dim + 1) * dscale
    assert np.all(np.abs(fd - g) <= 1e-6 * np.abs(g) + 1e-8 * scale)

    # direction: for a decreasing kernel grad_x W points along -dx, towards the node x'
    if kernel.nonnegative:
        assert np.all(dwdr < 0)
        np.testing.assert_allclose(g / np.linalg.norm(g, axis=1)[:, None], -u, rtol=0, atol=1e-12)

    # at dx = 0 the gradient is finite: zero, or Johnson's cusp set to zero by symmetry
    g0 = kernel.gradient(np.zeros((1, dim)), h)
    assert g0.shape == (1, dim) and np.all(g0 == 0.0)
    # a single 1-D offset is read as one point in len(dx) dimensions
    assert kernel.gradient(dx[0], h).shape == (1, dim)
