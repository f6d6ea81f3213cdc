"""Convergence rates from measured errors: power-law fits and pairwise observed orders.

An error that behaves like ``e = C h**p`` is a straight line in log-log; :func:`fit_power_law`
fits it by least squares over all points, :func:`observed_orders` gives the slope between each
pair of consecutive points, and :func:`observed_order` gives the two numbers a refinement study
reports: the least-squares order over all levels and the order between the two finest levels.

>>> fit = fit_power_law([0.1, 0.2, 0.4], [0.02, 0.08, 0.32])
>>> round(fit.exponent, 6), round(fit.prefactor, 6), fit.n_points
(2.0, 2.0, 3)
>>> observed_orders([0.4, 0.2, 0.1], [0.32, 0.08, 0.02]).round(6).tolist()
[2.0, 2.0]
>>> observed_order([0.4, 0.2, 0.1], [1.6e-2, 4e-3, 1e-3])
ObservedOrder(least_squares=2.0, finest_pair=2.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, NamedTuple

import numpy as np

__all__ = [
    "ROUNDOFF",
    "ObservedOrder",
    "PowerLawFit",
    "fit_power_law",
    "observed_order",
    "observed_orders",
]

#: Errors below this are round-off; they are skipped by the power-law fits.
ROUNDOFF = 1e-13


@dataclass(frozen=True)
class PowerLawFit:
    """Least-squares fit of ``log y = log C + p log x`` (``y = C x**p``).

    ``exponent`` is the slope ``p``, ``coefficient`` the prefactor ``C``, ``r2`` the coefficient
    of determination of the log-log fit (the fit quality), ``n_points`` the number of points
    used and ``x_min``/``x_max`` their range. No fit: ``exponent = nan`` (see :attr:`ok`).
    """

    exponent: float
    coefficient: float
    r2: float
    n_points: int
    x_min: float = math.nan
    x_max: float = math.nan

    @property
    def ok(self) -> bool:
        """True when a fit was made (enough usable points)."""
        return math.isfinite(self.exponent)

    @property
    def slope(self) -> float:
        """The fitted exponent ``p`` (slope in log-log); same as :attr:`exponent`."""
        return self.exponent

    @property
    def prefactor(self) -> float:
        """The fitted prefactor ``C``; same as :attr:`coefficient`."""
        return self.coefficient


def fit_power_law(
    x: Iterable[float], y: Iterable[float], floor: float = ROUNDOFF, min_points: int = 3
) -> PowerLawFit:
    """Fit ``y = C x**p`` by least squares in log-log, skipping ``y <= floor`` and non-finite data.

    Returns a fit with ``exponent = nan`` when fewer than ``min_points`` points remain (e.g. every
    error is at round-off). The exponent is rounded to 12 decimals.

    >>> fit_power_law([1, 2, 4, 8], [3.0, 1.5, 0.75, 0.375]).exponent
    -1.0
    """
    x = np.asarray(list(x), dtype=float)
    y = np.asarray(list(y), dtype=float)
    keep = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > floor)
    n = int(keep.sum())
    if n < min_points or np.unique(x[keep]).size < 2:
        return PowerLawFit(math.nan, math.nan, math.nan, n)
    lx, ly = np.log(x[keep]), np.log(y[keep])
    p, c = np.polyfit(lx, ly, 1)
    resid = ly - (p * lx + c)
    ss = float(np.sum((ly - ly.mean()) ** 2))
    r2 = 1.0 - float(np.sum(resid**2)) / ss if ss > 0 else 1.0
    return PowerLawFit(
        float(round(p, 12)), float(np.exp(c)), r2, n, float(x[keep].min()), float(x[keep].max())
    )


def observed_orders(h: Iterable[float], err: Iterable[float]) -> np.ndarray:
    """Pairwise observed orders ``log(e[i+1] / e[i]) / log(h[i+1] / h[i])``, in the given order.

    Returns an array of ``len(h) - 1`` orders; an entry is NaN where either error or spacing is
    not finite and positive, or the two spacings are equal.

    >>> observed_orders([1.0, 0.5, 0.25], [1.0, 0.5, 0.0]).tolist()
    [1.0, nan]
    """
    h = np.asarray(list(h), dtype=float)
    e = np.asarray(list(err), dtype=float)
    if h.shape != e.shape or h.ndim != 1:
        raise ValueError("h and err must be 1D sequences of the same length")
    out = np.full(max(h.size - 1, 0), math.nan)
    for i in range(out.size):
        h0, h1, e0, e1 = h[i], h[i + 1], e[i], e[i + 1]
        if all(np.isfinite(v) and v > 0 for v in (h0, h1, e0, e1)) and h0 != h1:
            out[i] = math.log(e1 / e0) / math.log(h1 / h0)
    return out


class ObservedOrder(NamedTuple):
    """Observed order of convergence of a refinement series (``error ~ C h**p``).

    ``least_squares`` is the slope of ``log error`` against ``log h`` over all usable levels
    (:func:`fit_power_law`), ``finest_pair`` the slope between the two smallest spacings. Both
    are NaN when fewer than two usable levels remain.
    """

    least_squares: float
    finest_pair: float


def observed_order(
    spacings: Iterable[float], errors: Iterable[float], floor: float = ROUNDOFF
) -> ObservedOrder:
    """Least-squares order over all levels and the order between the two finest levels.

    Levels whose error is at or below ``floor`` (round-off) or not finite, or whose spacing is
    not finite and positive, are dropped first; the rest are sorted by spacing. Both orders are
    rounded to 12 decimals (NaN with fewer than two distinct usable spacings).

    >>> observed_order([0.2, 0.1], [1e-14, 1e-15]).least_squares  # round-off is not fitted
    nan
    """
    h = np.asarray(list(spacings), dtype=float)
    e = np.asarray(list(errors), dtype=float)
    if h.shape != e.shape or h.ndim != 1:
        raise ValueError("spacings and errors must be 1D sequences of the same length")
    keep = np.isfinite(h) & np.isfinite(e) & (h > 0) & (e > floor)
    h, e = h[keep], e[keep]
    if h.size < 2 or np.unique(h).size < 2:
        return ObservedOrder(math.nan, math.nan)
    order = np.argsort(h)
    h, e = h[order], e[order]
    fit = fit_power_law(h, e, floor=floor, min_points=2)
    finest = observed_orders(h[:2], e[:2])[0]
    return ObservedOrder(fit.exponent, round(float(finest), 12))
