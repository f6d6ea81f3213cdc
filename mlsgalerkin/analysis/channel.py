r"""The velocity profile of a channel flow on a particle lattice against an exact solution.

A channel between walls at ``y = 0`` and ``y = H`` is cut into ``H/Δx`` rows, each ``Δx`` thick
(the rows of the particle lattice). :func:`row_means` averages the particles' height and x velocity
over each row, giving the profile ``(y_k, u_k)``. :func:`channel_profile_errors` compares it with
the exact profile ``e_k = u_exact(y_k)`` in units of a speed scale ``U`` (the wall speed, the
centre speed):

.. math::

    d_k = \frac{u_k - e_k}{U}, \qquad
    \max_k |d_k|, \qquad \Big(\frac{1}{K}\sum_k d_k^2\Big)^{1/2},

and splits the deviation into a smooth part and a row-to-row alternation with the three-row filter
``F(u)_k = ¼ u_{k−1} + ½ u_k + ¼ u_{k+1}`` (over the inner rows ``k = 1 … K−2``; it removes an
alternation ``(−1)^k`` entirely and leaves a profile linear in ``k`` unchanged):

.. math::

    s_k = \frac{F(u)_k - F(e)_k}{U}, \qquad a_k = d_k - F(d)_k,

the smooth part's largest ``max_k |s_k|`` and the alternation's amplitude ``max_k |a_k|``.

>>> import numpy as np
>>> y = (np.arange(8) + 0.5) / 8
>>> exact = y.copy()
>>> u = exact + 0.01 * (-1.0) ** np.arange(8)
>>> e = channel_profile_errors(y, u, exact, scale=1.0, height=1.0)
>>> round(e.max, 6), round(e.max_smooth, 6), round(e.alternation, 6)
(0.01, 0.0, 0.01)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ChannelProfileErrors", "channel_profile_errors", "row_means", "three_row_filter"]


def row_means(y: ArrayLike, u: ArrayLike, height: float, spacing: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean height and mean value of the particles in each row ``spacing`` thick of a channel
    ``height`` high.

    ``y`` (m) and ``u`` (any unit, e.g. the x velocity in m/s) have shape ``(n,)``: the particles'
    heights and values. The rows are ``k = ⌊y/Δx⌋`` clipped to ``0 … round(H/Δx) − 1`` (a particle
    a little outside the channel joins the nearest row). Returns ``(y_k, u_k)``, each of shape
    ``(K,)``, ``K`` the number of rows holding at least one particle, bottom row first; empty rows
    are left out."""
    y = np.asarray(y)
    u = np.asarray(u)
    rows = int(round(height / spacing))
    k = np.clip((y / spacing).astype(int), 0, rows - 1)
    count = np.bincount(k, minlength=rows)
    keep = count > 0
    mean_y = np.bincount(k, y, minlength=rows)[keep] / count[keep]
    mean_u = np.bincount(k, u, minlength=rows)[keep] / count[keep]
    return mean_y, mean_u


def three_row_filter(u: ArrayLike) -> NDArray[np.float64]:
    """``¼ u[k−1] + ½ u[k] + ¼ u[k+1]`` over the inner rows: shape ``(K,)`` -> ``(K − 2,)``, same
    unit. It removes a row-to-row alternation ``(−1)^k`` and keeps a profile linear in ``k``."""
    u = np.asarray(u)
    return 0.25 * u[:-2] + 0.5 * u[1:-1] + 0.25 * u[2:]


@dataclass(frozen=True)
class ChannelProfileErrors:
    """The deviation of a row profile from the exact one (:func:`channel_profile_errors`); the
    errors are fractions of the speed scale ``U`` (0.01 is 1 %)."""

    max: float                 #: largest |u_k − e_k| / U over the rows (–)
    rms: float                 #: RMS of (u_k − e_k) / U over the rows (–)
    max_smooth: float          #: largest |F(u)_k − F(e)_k| / U over the inner rows (–)
    alternation: float         #: largest |d_k − F(d)_k| over the inner rows: the row-to-row alternation (–)
    centre_speed: float        #: u_k of the row nearest mid-height (m/s)
    centre_speed_exact: float  #: e_k of that row (m/s)
    rows: int                  #: number of rows K (–)

    def results(self) -> dict[str, float]:
        """The problems' result keys for these errors, in the order they report them."""
        return {
            "profile_error_max": self.max,
            "profile_error_rms": self.rms,
            "profile_error_max_smooth": self.max_smooth,
            "row_alternation_amplitude": self.alternation,
            "centre_speed_m_s": self.centre_speed,
            "centre_speed_exact_m_s": self.centre_speed_exact,
        }

    def headline(self, scale_name: str, time: float, steady_fraction: float, reynolds: float) -> str:
        """One line for a run's headline: the largest and RMS deviation in % of ``scale_name`` at
        ``time`` (s), the flow's approach to steady (``steady_fraction``, a fraction), the smooth
        part, the alternation and the Reynolds number."""
        return (f"velocity profile within {100 * self.max:.2f} % of {scale_name} of the start-up series "
                f"at t = {time:.3g} s (RMS {100 * self.rms:.2f} %; the flow at "
                f"{100 * steady_fraction:.0f} % of steady); smooth part within "
                f"{100 * self.max_smooth:.2f} %, row-to-row alternation "
                f"{100 * self.alternation:.2f} %; Re = {reynolds:g}")


def channel_profile_errors(y: ArrayLike, u: ArrayLike, exact: ArrayLike, scale: float,
                           height: float) -> ChannelProfileErrors:
    """The deviation of the row profile ``u`` (m/s) at the row heights ``y`` (m) from the exact
    profile ``exact`` (m/s) at the same heights, in units of the speed ``scale`` (m/s) (module
    docstring: ``d``, its smooth part ``s`` and the alternation ``a``). ``y``, ``u`` and ``exact``
    have shape ``(K,)``, ``K ≥ 3`` rows (:func:`row_means`); ``height`` (m) is the channel's, whose
    middle row gives the centre speed."""
    y = np.asarray(y)
    u = np.asarray(u)
    exact = np.asarray(exact)
    if not (y.ndim == 1 and y.shape == u.shape == exact.shape and y.size >= 3):
        raise ValueError(f"y, u and exact must be 1-D of one length, at least 3 rows; got shapes {y.shape}, "
                         f"{u.shape}, {exact.shape}: pass the row profile of row_means")
    dev = (u - exact) / scale
    centre = int(np.argmin(np.abs(y - 0.5 * height)))
    smooth = (three_row_filter(u) - three_row_filter(exact)) / scale
    alternation = dev[1:-1] - three_row_filter(dev)
    return ChannelProfileErrors(
        max=float(np.max(np.abs(dev))),
        rms=float(np.sqrt(np.mean(dev**2))),
        max_smooth=float(np.max(np.abs(smooth))),
        alternation=float(np.max(np.abs(alternation))),
        centre_speed=float(u[centre]),
        centre_speed_exact=float(exact[centre]),
        rows=int(y.size),
    )
