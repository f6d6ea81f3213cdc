r"""Regular waves from gauge records: harmonic amplitudes and the split of incident and reflected waves.

Pure numpy functions, for the wave problems' analyses and the verification scripts. Times in
seconds, positions and elevations in metres; a wave of angular frequency ``ω`` (rad/s) and wave
number ``k`` (1/m) runs along ``+x``.

:func:`harmonic_fit` fits a record with its mean, the first and the second harmonic of ``ω``;
:func:`complex_amplitude` returns the first harmonic as one complex number,
``η(t) ≈ c + Re(A e^{iωt})``.

:func:`incident_reflected` splits the first harmonic measured at three or more gauges (two at
least) into the wave running along ``+x`` (incident, amplitude ``a_I``) and the one running back
(reflected, ``a_R``), by least squares over the gauges (Mansard & Funke 1980; with two gauges it is
the method of Goda & Suzuki 1976):

.. math::
    A_j = a_I\, e^{-ik x_j} + a_R\, e^{ik x_j},\qquad
    \min_{a_I, a_R} \sum_j \big|A_j - a_I e^{-ik x_j} - a_R e^{ik x_j}\big|^2,

and the reflection coefficient is ``K_R = |a_R| / |a_I|``. The split fails when every gauge pair
is a multiple of half a wavelength apart (``k Δx = nπ``): the two waves then look alike at the
gauges. Mansard & Funke recommend gauges at ``x₁``, ``x₁ + L/10`` and ``x₁ + L/4`` (``L = 2π/k``).

>>> k, omega = 2 * np.pi / 1.2, 2 * np.pi
>>> x = np.array([1.0, 1.12, 1.3])
>>> t = np.linspace(0.0, 10.0, 2001)
>>> records = [0.01 * np.cos(omega * t - k * xj) + 0.002 * np.cos(omega * t + k * xj + 0.3) for xj in x]
>>> split = incident_reflected(x, [complex_amplitude(t, r, omega) for r in records], k)
>>> round(abs(split.incident), 6), round(abs(split.reflected), 6), round(split.reflection_coefficient, 6)
(0.01, 0.002, 0.2)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["IncidentReflected", "complex_amplitude", "gauge_positions", "harmonic_fit", "incident_reflected"]


def harmonic_fit(t: ArrayLike, eta: ArrayLike, omega: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Least-squares :math:`η ≈ c + a \cos ωt + b \sin ωt + a_2 \cos 2ωt + b_2 \sin 2ωt`: the
    coefficients ``(c, a, b, a₂, b₂)`` (unit of ``eta``) and the residuals at the samples.

    ``t``, ``eta`` of shape ``(n,)``, ``n ≥ 5``; ``omega`` in rad per unit of ``t``.
    """
    t, eta = np.asarray(t, dtype=float), np.asarray(eta, dtype=float)
    A = np.column_stack([np.ones(t.size), np.cos(omega * t), np.sin(omega * t),
                         np.cos(2 * omega * t), np.sin(2 * omega * t)])
    coef, *_ = np.linalg.lstsq(A, eta, rcond=None)
    return coef, eta - A @ coef


def complex_amplitude(t: ArrayLike, eta: ArrayLike, omega: float) -> complex:
    r"""The first harmonic of ``eta`` as ``A`` with :math:`η ≈ c + \mathrm{Re}(A e^{iωt})` (plus the
    second harmonic, fitted alongside): ``A = a − i b`` from :func:`harmonic_fit`."""
    coef, _ = harmonic_fit(t, eta, omega)
    return complex(coef[1], -coef[2])


@dataclass(frozen=True)
class IncidentReflected:
    """The split of :func:`incident_reflected`: complex amplitudes at ``x = 0`` (m) of the wave
    running along ``+x`` (``incident``) and back (``reflected``), the reflection coefficient
    ``|a_R|/|a_I|``, and the RMS misfit of the two-wave model over the gauges relative to the
    incident amplitude (0 for exactly two gauges; a few per cent for clean regular waves)."""

    incident: complex
    reflected: complex
    reflection_coefficient: float
    relative_misfit: float


def incident_reflected(x: ArrayLike, amplitudes: Sequence[complex] | ArrayLike, k: float) -> IncidentReflected:
    r"""Split first-harmonic amplitudes ``A_j`` (complex, :func:`complex_amplitude`) measured at the
    gauge positions ``x_j`` (m, shape ``(n,)``, ``n ≥ 2``) into incident and reflected waves of wave
    number ``k`` (1/m): least squares of :math:`A_j = a_I e^{-ikx_j} + a_R e^{ikx_j}` (module
    docstring).

    Raises ``ValueError`` for fewer than two gauges or gauges that cannot tell the two waves apart
    (every pair a multiple of half a wavelength apart).
    """
    x = np.asarray(x, dtype=float)
    A = np.asarray(amplitudes, dtype=complex)
    if x.ndim != 1 or x.size < 2 or A.shape != x.shape:
        raise ValueError(f"incident_reflected needs two or more gauge positions with one amplitude each, "
                         f"got {x.size} positions and {A.size} amplitudes")
    design = np.column_stack([np.exp(-1j * k * x), np.exp(1j * k * x)])
    singular = np.linalg.svd(design, compute_uv=False)
    if singular[-1] < 1e-3 * singular[0]:
        raise ValueError(f"the gauges at x = {x.tolist()} m cannot separate incident and reflected waves of "
                         f"wavelength {2 * math.pi / k:.4g} m (every pair about a multiple of half a wavelength "
                         f"apart); space them by about a tenth and a quarter of a wavelength")
    (a_i, a_r), *_ = np.linalg.lstsq(design, A, rcond=None)
    misfit = float(np.sqrt(np.mean(np.abs(A - design @ np.array([a_i, a_r])) ** 2)))
    incident = float(abs(a_i))
    return IncidentReflected(complex(a_i), complex(a_r), float(abs(a_r)) / incident if incident > 0 else math.nan,
                             misfit / incident if incident > 0 else math.nan)


def gauge_positions(centre: float, wavelength: float) -> NDArray[np.float64]:
    """Three gauges for :func:`incident_reflected` around ``centre`` (m): ``x₁``, ``x₁ + L/10``,
    ``x₁ + L/4`` with ``x₁ = centre − L/8`` (Mansard & Funke 1980's spacing), shape ``(3,)``."""
    x1 = centre - wavelength / 8.0
    return np.array([x1, x1 + wavelength / 10.0, x1 + wavelength / 4.0])
