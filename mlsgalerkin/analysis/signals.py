r"""Signal analysis of time series: periods, running means, windows.

Pure numpy functions over 1-D arrays, for problems' analyses and the verification scripts. The
time axis ``t`` is increasing (any unit, seconds unless said otherwise; the results come in its
unit); samples may be unevenly spaced unless a function says otherwise. A function that cannot
measure what it is asked for returns NaN (a period) or an empty list (windows): the caller says
why in its results.

Periods
    :func:`upward_crossings` (times where a signal crosses zero upward), :func:`crossing_period`
    (mean period between upward crossings of the signal's own mean), :func:`spectral_period`
    (the peak of the amplitude spectrum).
Smoothing
    :func:`running_mean` (centred window on the samples themselves), :func:`grid_average`
    (resampled on a uniform grid, then a centred moving average).
Windows
    :func:`threshold_windows` (intervals where ``|y|`` exceeds a level, short gaps merged),
    :func:`half_height_window` (the interval around a peak where the signal stays above half the
    peak's height over a base).

>>> t = np.linspace(0.0, 4.0, 4001)
>>> period, periods = crossing_period(t, np.sin(2 * np.pi * (t - 0.1) / 0.5))
>>> round(period, 6), periods   # upward crossings at 0.1, 0.6, ..., 3.6
(0.5, 7)
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "crossing_period",
    "grid_average",
    "half_height_window",
    "running_mean",
    "spectral_period",
    "threshold_windows",
    "upward_crossings",
]


def upward_crossings(t: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
    r"""Times where ``y`` crosses zero upward, by linear interpolation between the samples:
    for each ``k`` with ``y_k < 0 ≤ y_{k+1}``, :math:`t_c = t_k - y_k (t_{k+1} - t_k)/(y_{k+1} - y_k)`.

    ``t``, ``y`` of shape ``(n,)``; returns shape ``(m,)`` in the unit of ``t``.
    """
    t, y = np.asarray(t), np.asarray(y)
    k = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def crossing_period(t: ArrayLike, y: ArrayLike) -> tuple[float, int]:
    r"""Mean period of ``y`` from its upward crossings of its own mean, and the number of periods
    it is measured over: with crossing times :math:`t_{c,0} < … < t_{c,m}` of ``y − ȳ``, the period
    is :math:`(t_{c,m} - t_{c,0})/m` (the mean of the differences) over ``m`` periods.

    Returns ``(nan, 0)`` with fewer than 3 samples or fewer than two crossings. Unit: that of ``t``.
    """
    t, y = np.asarray(t), np.asarray(y)
    if t.size < 3:
        return math.nan, 0
    tc = upward_crossings(t, y - y.mean())
    return (float(np.diff(tc).mean()), int(tc.size - 1)) if tc.size >= 2 else (math.nan, 0)


def spectral_period(t: ArrayLike, y: ArrayLike, *, samples: int | None = None, detrend: int = 1,
                    hann: bool = True, pad: int = 1, band: tuple[float, float] | None = None,
                    refine: bool = False) -> float:
    r"""The period of the strongest oscillation of ``y``: the peak of its amplitude spectrum.

    The series is resampled evenly (linear interpolation) on ``samples`` points over
    ``[t_0, t_{n-1}]`` (default: as many as it has), its polynomial trend of degree ``detrend``
    removed (least squares), multiplied by a Hann window if ``hann``, and zero-padded to
    ``pad`` times its length; the amplitude :math:`|Y(f)|` of its real FFT is searched for its
    largest value, over the frequencies :math:`1/\text{band}_1 ≤ f ≤ 1/\text{band}_0` if ``band``
    (periods, in the unit of ``t``) is given, else over every frequency above zero. With ``refine``
    the peak bin ``k`` is moved by the vertex of the parabola through bins ``k−1, k, k+1``:
    :math:`δ = \tfrac12 (a − c)/(a − 2b + c)`, :math:`f = f_k + δ Δf`. Returns :math:`1/f`.

    NaN when ``band`` holds fewer than three frequency bins. ``t``, ``y`` of shape ``(n,)``,
    ``n ≥ 2``.
    """
    t, y = np.asarray(t), np.asarray(y)
    tt = np.linspace(t[0], t[-1], int(t.size if samples is None else samples))
    yy = np.interp(tt, t, y)
    yy = yy - np.polyval(np.polyfit(tt, yy, detrend), tt)
    if hann:
        yy = yy * np.hanning(tt.size)
    n = pad * tt.size
    amp = np.abs(np.fft.rfft(yy, n))
    freq = np.fft.rfftfreq(n, tt[1] - tt[0])
    if band is None:
        k = 1 + int(np.argmax(amp[1:]))
    else:
        inside = np.flatnonzero((freq >= 1.0 / band[1]) & (freq <= 1.0 / band[0]))
        if inside.size < 3:
            return math.nan
        k = int(inside[np.argmax(amp[inside])])
    if not refine or k + 1 >= amp.size:
        return float(1.0 / freq[k])
    a, b, c = amp[k - 1], amp[k], amp[k + 1]
    shift = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) != 0 else 0.0
    return float(1.0 / (freq[k] + shift * (freq[1] - freq[0])))


def running_mean(t: ArrayLike, y: ArrayLike, window: float) -> NDArray[np.float64]:
    r"""Mean of ``y`` over the samples in :math:`[t_i − w/2, t_i + w/2]` at each sample ``i``
    (uneven spacing allowed; a plain mean of the samples, not a time integral), by cumulative sums.

    ``t``, ``y`` of shape ``(n,)``; ``window`` ``w`` in the unit of ``t``; returns shape ``(n,)``.
    """
    t, y = np.asarray(t), np.asarray(y)
    c = np.concatenate([[0.0], np.cumsum(y)])
    lo = np.searchsorted(t, t - 0.5 * window, side="left")
    hi = np.searchsorted(t, t + 0.5 * window, side="right")
    return (c[hi] - c[lo]) / np.maximum(hi - lo, 1)


def grid_average(t: ArrayLike, y: ArrayLike, span: float, step: float = 1.0e-3,
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""``y`` resampled (linear interpolation) on the uniform grid :math:`t_0, t_0 + s, …` up to
    :math:`t_{n-1}` of step ``s = step`` and averaged over a centred window of
    :math:`k = \max(1, \text{round}(\text{span}/s))` grid points (the ends padded with the end
    values). Returns ``(grid, mean)``, both of shape ``(m,)``; ``span``, ``step`` in the unit of ``t``.
    """
    grid = np.arange(float(t[0]), float(t[-1]) + 0.5 * step, step)
    k = max(1, int(round(span / step)))
    y_grid = np.interp(grid, t, y)
    padded = np.pad(y_grid, (k // 2, k - 1 - k // 2), mode="edge")
    return grid, np.convolve(padded, np.ones(k) / k, mode="valid")


def threshold_windows(t: ArrayLike, y: ArrayLike, level: float, gap: float = 0.3) -> list[tuple[float, float]]:
    """The intervals ``(start, end)`` of the samples where ``|y| > level``, merged across gaps of at
    most ``gap`` (unit of ``t``) between such samples; ``[]`` when none exceeds the level."""
    t = np.asarray(t)
    on = np.abs(np.asarray(y)) > level
    out: list[list[float]] = []
    for k in np.flatnonzero(on):
        if out and t[k] - out[-1][1] <= gap:
            out[-1][1] = float(t[k])
        else:
            out.append([float(t[k]), float(t[k])])
    return [(a, b) for a, b in out]


def half_height_window(y: ArrayLike, peak: int, base: float) -> tuple[int, int]:
    """The sample indices ``(a, b)`` of the interval around sample ``peak`` where ``y`` stays above
    half the peak's height over ``base``, ``base + (y[peak] − base)/2`` (both ends included)."""
    y = np.asarray(y)
    half = base + 0.5 * (y[peak] - base)
    a = b = peak
    while a > 0 and y[a - 1] > half:
        a -= 1
    while b < y.size - 1 and y[b + 1] > half:
        b += 1
    return a, b
