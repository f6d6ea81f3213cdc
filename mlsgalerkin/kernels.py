r"""Kernel (window, weight) functions.

Every kernel is written

.. math:: W(r, h) = \frac{\alpha_d}{h^d} f(q), \qquad q = r / h,

with compact support ``q < support`` (the :math:`\kappa` of Liu & Liu 2003 and Xing 2019) and the normalisation
constant :math:`\alpha_d` that makes :math:`\int W\,dV = 1` in ``d`` dimensions. MLS and RKPM
shape functions do not need :math:`\alpha_d` (it cancels), SPH sums do.

Example
-------
>>> from mlsgalerkin.kernels import get_kernel
>>> k = get_kernel("cubic_spline")
>>> round(float(k.value(0.0, h=1.0, dim=2)), 12)  # = 10 / (7 pi)
0.454728408834

The numpy formulas in :data:`_SHAPES` are the readable reference; :func:`kernel_f_df` is the
numba scalar version used inside compiled loops, selected by ``Kernel.kernel_id``. A test checks
that both agree for every kernel.

Constants follow Xing (2019) and Liu & Liu (2003), corrected where they are wrong: Lucy's 3D constant carries the
factor :math:`\pi`; the super-Gaussian uses the dimension-general factor :math:`(d/2 + 1 - q^2)`;
the quintic 3D constant is the exact :math:`1/(120\pi)`. Wendland kernels use the common SPH
convention with support ``q < 2`` and the 1D functions :math:`\psi_{1,k}` in 1D.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "Kernel",
    "KERNELS",
    "SPH_STUDY_KERNELS",
    "get_kernel",
    "kernel_names",
    "kernel_f_df",
]

FloatArray = NDArray[np.float64]

# --------------------------------------------------------------------------------------
# numpy reference shapes f(q, dim) and df/dq(q, dim); q >= 0, support handled by caller
# --------------------------------------------------------------------------------------


def _pos(x: FloatArray) -> FloatArray:
    return np.maximum(x, 0.0)


def _quadratic(q, d):
    return 1.0 - q**2, -2.0 * q


def _lucy(q, d):
    return (1.0 + 3.0 * q) * (1.0 - q) ** 3, -12.0 * q * (1.0 - q) ** 2


def _johnson(q, d):
    return 3.0 / 16.0 * q**2 - 0.75 * q + 0.75, 3.0 / 8.0 * q - 0.75


def _gaussian(q, d):
    e = np.exp(-(q**2))
    return e, -2.0 * q * e


def _super_gaussian(q, d):
    e = np.exp(-(q**2))
    a = d / 2.0 + 1.0
    return (a - q**2) * e, (-2.0 * q - 2.0 * q * (a - q**2)) * e


def _cubic(q, d):
    a, b = _pos(1.0 - q), _pos(2.0 - q)
    return 0.25 * b**3 - a**3, -0.75 * b**2 + 3.0 * a**2


def _quartic_spline(q, d):
    a, b, c = _pos(2.5 - q), _pos(1.5 - q), _pos(0.5 - q)
    return a**4 - 5.0 * b**4 + 10.0 * c**4, -4.0 * a**3 + 20.0 * b**3 - 40.0 * c**3


def _quintic(q, d):
    a, b, c = _pos(3.0 - q), _pos(2.0 - q), _pos(1.0 - q)
    return a**5 - 6.0 * b**5 + 15.0 * c**5, -5.0 * a**4 + 30.0 * b**4 - 75.0 * c**4


def _new_quartic(q, d):
    f = 2.0 / 3.0 - 9.0 / 8.0 * q**2 + 19.0 / 24.0 * q**3 - 5.0 / 32.0 * q**4
    df = -9.0 / 4.0 * q + 19.0 / 8.0 * q**2 - 5.0 / 8.0 * q**3
    return f, df


def _wendland_c2(q, d):
    s = _pos(1.0 - 0.5 * q)
    if d == 1:
        return s**3 * (1.5 * q + 1.0), -3.0 * q * s**2
    return s**4 * (2.0 * q + 1.0), -5.0 * q * s**3


def _wendland_c4(q, d):
    s = _pos(1.0 - 0.5 * q)
    if d == 1:
        return s**5 * (2.0 * q**2 + 2.5 * q + 1.0), -s**4 * (7.0 * q**2 + 3.5 * q)
    return s**6 * (35.0 / 12.0 * q**2 + 3.0 * q + 1.0), -s**5 * (35.0 / 3.0 * q**2 + 14.0 / 3.0 * q)


_SHAPES: dict[int, Callable] = {
    0: _quadratic,
    1: _lucy,
    2: _johnson,
    3: _gaussian,
    4: _super_gaussian,
    5: _cubic,
    6: _quartic_spline,
    7: _quintic,
    8: _new_quartic,
    9: _wendland_c2,
    10: _wendland_c4,
}

# --------------------------------------------------------------------------------------
# numba scalar dispatch (hot loops)
# --------------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always")
def kernel_f_df(kernel_id: int, q: float, support: float, dim: int) -> tuple[float, float]:
    """Unnormalised shape ``f(q)`` and ``df/dq`` of kernel ``kernel_id``; zero for ``q >= support``."""
    if q >= support:
        return 0.0, 0.0
    if kernel_id == 5:  # cubic spline, the default: first for the branch predictor
        if q < 1.0:
            return 1.0 - 1.5 * q * q + 0.75 * q * q * q, -3.0 * q + 2.25 * q * q
        b = 2.0 - q
        return 0.25 * b * b * b, -0.75 * b * b
    if kernel_id == 0:
        return 1.0 - q * q, -2.0 * q
    if kernel_id == 1:
        a = 1.0 - q
        return (1.0 + 3.0 * q) * a * a * a, -12.0 * q * a * a
    if kernel_id == 2:
        return 0.1875 * q * q - 0.75 * q + 0.75, 0.375 * q - 0.75
    if kernel_id == 3:
        e = math.exp(-q * q)
        return e, -2.0 * q * e
    if kernel_id == 4:
        e = math.exp(-q * q)
        a = 0.5 * dim + 1.0 - q * q
        return a * e, (-2.0 * q - 2.0 * q * a) * e
    if kernel_id == 6:
        a = 2.5 - q
        f = a * a * a * a
        df = -4.0 * a * a * a
        if q < 1.5:
            b = 1.5 - q
            f -= 5.0 * b * b * b * b
            df += 20.0 * b * b * b
            if q < 0.5:
                c = 0.5 - q
                f += 10.0 * c * c * c * c
                df -= 40.0 * c * c * c
        return f, df
    if kernel_id == 7:
        a = 3.0 - q
        f = a**5
        df = -5.0 * a**4
        if q < 2.0:
            b = 2.0 - q
            f -= 6.0 * b**5
            df += 30.0 * b**4
            if q < 1.0:
                c = 1.0 - q
                f += 15.0 * c**5
                df -= 75.0 * c**4
        return f, df
    if kernel_id == 8:
        f = 2.0 / 3.0 - 1.125 * q * q + 19.0 / 24.0 * q**3 - 5.0 / 32.0 * q**4
        df = -2.25 * q + 2.375 * q * q - 0.625 * q**3
        return f, df
    if kernel_id == 9:
        s = 1.0 - 0.5 * q
        if dim == 1:
            return s**3 * (1.5 * q + 1.0), -3.0 * q * s * s
        return s**4 * (2.0 * q + 1.0), -5.0 * q * s**3
    if kernel_id == 10:
        s = 1.0 - 0.5 * q
        if dim == 1:
            return s**5 * (2.0 * q * q + 2.5 * q + 1.0), -(s**4) * (7.0 * q * q + 3.5 * q)
        return s**6 * (35.0 / 12.0 * q * q + 3.0 * q + 1.0), -(s**5) * (
            35.0 / 3.0 * q * q + 14.0 / 3.0 * q
        )
    return 0.0, 0.0


# --------------------------------------------------------------------------------------
# Kernel objects and registry
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Kernel:
    """A radial kernel ``W(r, h) = alpha_d / h**d * f(r / h)`` with support ``q < support``.

    Attributes
    ----------
    name : registry name, e.g. ``"cubic_spline"``.
    kernel_id : integer used by compiled code (:func:`kernel_f_df`).
    support : support radius in units of ``h`` (kappa in Liu & Liu 2003 and Xing 2019).
    alpha : normalisation constants ``(alpha_1, alpha_2, alpha_3)``.
    smoothness : continuity of ``W`` as a function of position, in words.
    nonnegative : False where ``f`` changes sign inside the support (super-Gaussian): such a
        kernel cannot serve as an MLS/RKPM weight.
    exact_unity : False where ``∫W dV = 1`` holds only before truncation (Gaussians).
    reference : literature source.
    """

    name: str
    kernel_id: int
    support: float
    alpha: tuple[float, float, float]
    smoothness: str
    nonnegative: bool = True
    exact_unity: bool = True
    reference: str = ""

    def normalisation(self, dim: int) -> float:
        """The constant ``alpha_d`` (``W = alpha_d / h**d * f(q)``)."""
        _check_dim(dim)
        return self.alpha[dim - 1]

    def shape(self, q: ArrayLike, dim: int = 2) -> FloatArray:
        """Unnormalised ``f(q)``, zero for ``q >= support`` (numpy reference)."""
        q = np.abs(np.asarray(q, dtype=float))
        inside = q < self.support
        f, _ = _SHAPES[self.kernel_id](np.where(inside, q, 0.0), dim)
        return np.where(inside, f, 0.0)

    def shape_derivative(self, q: ArrayLike, dim: int = 2) -> FloatArray:
        """``df/dq``, zero for ``q >= support`` (numpy reference)."""
        q = np.abs(np.asarray(q, dtype=float))
        inside = q < self.support
        _, df = _SHAPES[self.kernel_id](np.where(inside, q, 0.0), dim)
        return np.where(inside, df, 0.0)

    def value(self, r: ArrayLike, h: ArrayLike, dim: int) -> FloatArray:
        """Normalised ``W(r, h)`` in units of 1/length**dim."""
        h = np.asarray(h, dtype=float)
        return self.normalisation(dim) / h**dim * self.shape(np.asarray(r) / h, dim)

    def derivative(self, r: ArrayLike, h: ArrayLike, dim: int) -> FloatArray:
        """``dW/dr = alpha_d / h**(d+1) * f'(r/h)``."""
        h = np.asarray(h, dtype=float)
        return self.normalisation(dim) / h ** (dim + 1) * self.shape_derivative(np.asarray(r) / h, dim)

    def gradient(self, dx: ArrayLike, h: ArrayLike) -> FloatArray:
        """``∇W`` with respect to ``x`` for offsets ``dx = x - x'`` of shape ``(n, dim)``."""
        dx = np.atleast_2d(np.asarray(dx, dtype=float))
        dim = dx.shape[1]
        r = np.linalg.norm(dx, axis=1)
        dwdr = self.derivative(r, np.broadcast_to(h, r.shape), dim)
        with np.errstate(invalid="ignore", divide="ignore"):
            unit = np.where(r[:, None] > 0, dx / np.where(r > 0, r, 1.0)[:, None], 0.0)
        return dwdr[:, None] * unit

    def with_support(self, support: float, renormalise: bool = False) -> "Kernel":
        """A copy truncated at ``support`` (only meaningful for the Gaussian family).

        With ``renormalise=True`` the constants are recomputed so that the truncated kernel
        integrates to one.
        """
        if support <= 0:
            raise ValueError(f"support must be positive, got {support}")
        k = replace(self, support=float(support))
        return k.renormalised() if renormalise else k

    def renormalised(self) -> "Kernel":
        """A copy whose constants make ``∫W dV = 1`` over the (truncated) support exactly."""
        alpha = tuple(1.0 / unnormalised_integral(self, d) for d in (1, 2, 3))
        return replace(self, alpha=alpha, exact_unity=True)


def unnormalised_integral(kernel: Kernel, dim: int) -> float:
    """``∫ f(|x|) dx`` over the support in ``dim`` dimensions (Gauss-Legendre, per piece)."""
    from scipy.integrate import quad

    surface = {1: 2.0, 2: 2.0 * math.pi, 3: 4.0 * math.pi}[dim]
    breaks = [b for b in (0.5, 1.0, 1.5, 2.0, 2.5) if b < kernel.support]
    total, _ = quad(
        lambda q: float(kernel.shape(q, dim)) * q ** (dim - 1),
        0.0,
        kernel.support,
        points=breaks or None,
        epsabs=1e-14,
        epsrel=1e-13,
        limit=200,
    )
    return surface * total


def _check_dim(dim: int) -> None:
    if dim not in (1, 2, 3):
        raise ValueError(f"dim must be 1, 2 or 3, got {dim!r}")


_PI = math.pi

KERNELS: dict[str, Kernel] = {
    k.name: k
    for k in [
        Kernel("quadratic", 0, 1.0, (3 / 4, 2 / _PI, 15 / (8 * _PI)),
               "C0: dW/dr ≠ 0 at the support edge", reference="Hicks & Liebrock 2000"),
        Kernel("lucy_quartic", 1, 1.0, (5 / 4, 5 / _PI, 105 / (16 * _PI)), "C2",
               reference="Lucy 1977"),
        Kernel("johnson_quadratic", 2, 2.0, (1.0, 2 / _PI, 5 / (4 * _PI)),
               "C0: cusp at r = 0 (df/dq(0) ≠ 0)", reference="Johnson & Beissel 1996"),
        Kernel("gaussian", 3, 3.0, (1 / math.sqrt(_PI), 1 / _PI, _PI**-1.5),
               "C∞ inside; jump of e^-9 at the truncation q = 3", exact_unity=False,
               reference="Gingold & Monaghan 1977"),
        Kernel("super_gaussian", 4, 2.0, (1 / math.sqrt(_PI), 1 / _PI, _PI**-1.5),
               "C∞ inside; jump at the truncation q = 2; negative for q > sqrt(d/2+1)",
               nonnegative=False, exact_unity=False, reference="Monaghan 1985"),
        Kernel("cubic_spline", 5, 2.0, (2 / 3, 10 / (7 * _PI), 1 / _PI), "C2",
               reference="Monaghan & Lattanzio 1985"),
        Kernel("quartic_spline", 6, 2.5, (1 / 24, 96 / (1199 * _PI), 1 / (20 * _PI)), "C3",
               reference="Schoenberg M5; Liu & Liu 2003"),
        Kernel("quintic_spline", 7, 3.0, (1 / 120, 7 / (478 * _PI), 1 / (120 * _PI)), "C4",
               reference="Schoenberg M6; Morris 1997"),
        Kernel("new_quartic", 8, 2.0, (1.0, 15 / (7 * _PI), 315 / (208 * _PI)),
               "C1: d2W/dr2 ≠ 0 at the edge; slightly negative (≥ -0.24 % of f(0)) "
               "for 1.6957 < q < 2", nonnegative=False, reference="Liu, Liu & Lam 2003"),
        Kernel("wendland_c2", 9, 2.0, (5 / 8, 7 / (4 * _PI), 21 / (16 * _PI)), "C2",
               reference="Wendland 1995; Dehnen & Aly 2012"),
        Kernel("wendland_c4", 10, 2.0, (3 / 4, 9 / (4 * _PI), 495 / (256 * _PI)), "C4",
               reference="Wendland 1995; Dehnen & Aly 2012"),
    ]
}

#: The nine kernels of the accuracy study of Xing (2019, §12.2.3).
SPH_STUDY_KERNELS: tuple[str, ...] = (
    "quadratic",
    "lucy_quartic",
    "johnson_quadratic",
    "gaussian",
    "super_gaussian",
    "cubic_spline",
    "quartic_spline",
    "quintic_spline",
    "new_quartic",
)


def kernel_names() -> list[str]:
    """Names of all registered kernels."""
    return list(KERNELS)


def get_kernel(kernel: str | Kernel) -> Kernel:
    """Look a kernel up by name (a :class:`Kernel` passes through unchanged)."""
    if isinstance(kernel, Kernel):
        return kernel
    try:
        return KERNELS[kernel]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown kernel {kernel!r}; choose one of: {', '.join(KERNELS)}"
        ) from None
