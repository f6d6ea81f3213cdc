r"""Periodic axes of a particle domain: the box, the minimum-image offset and the wrap.

A :class:`Periodic` names the axes along which the domain repeats, each with its interval
``[lower, upper)``: a particle leaving through ``upper`` re-enters at ``lower``, and two particles
near opposite ends are neighbours across the seam. Every pair offset of such a domain is the
*minimum image* of the plain difference, per periodic axis ``a`` with period
:math:`L_a = \mathrm{upper}_a - \mathrm{lower}_a`:

.. math::

    d_a \leftarrow d_a - L_a \,\lfloor d_a / L_a + 1/2 \rfloor ,

which maps ``d_a`` into ``[−L_a/2, L_a/2)``; the numba kernels receive the periods as a tuple of
three floats ``period`` (m) whose ``0.0`` entries mark the axes that are not periodic (their
offsets are left untouched, bit for bit). A tuple, not an array: it is passed by value, so the
compiled loops keep the three periods in registers (an array's entries would be reloaded at every
pair, as the loops also write arrays), and a run without periodic axes pays one comparison per
offset component. With a kernel support ``R`` no longer than ``L_a/2``
the minimum image is the only image within reach, so each pair is counted once.

>>> import numpy as np
>>> box = Periodic(x=(0.0, 1.0))
>>> box.period(2).tolist(), box.axes(2), kernel_period(box, 2)
([1.0, 0.0, 0.0], (0,), (1.0, 0.0, 0.0))
>>> x = np.array([[1.05, 0.3], [-0.2, 0.7]])
>>> box.wrap(x)
>>> np.round(x, 12).tolist()
[[0.05, 0.3], [0.8, 0.7]]
>>> minimum_image(np.array([[0.9, 0.1]]), box.period(2)).round(12).tolist()
[[-0.1, 0.1]]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["NO_PERIOD", "Periodic", "as_period", "kernel_period", "minimum_image"]

#: The kernels' ``period`` of a domain without periodic axes (three zeros).
NO_PERIOD = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Periodic:
    """The periodic axes of a domain, each as its interval ``(lower, upper)`` in metres.

    Parameters
    ----------
    x, y, z : (float, float), optional
        ``(lower, upper)`` of a periodic axis, ``upper > lower``; an axis left ``None`` is not
        periodic. ``Periodic(x=(0.0, 2.0))`` repeats the domain every 2 m along ``x``.
    """

    x: tuple[float, float] | None = None
    y: tuple[float, float] | None = None
    z: tuple[float, float] | None = None

    def intervals(self) -> tuple[tuple[float, float] | None, ...]:
        """``(x, y, z)`` intervals (``None`` for an axis that is not periodic)."""
        return (self.x, self.y, self.z)

    def axes(self, dim: int) -> tuple[int, ...]:
        """The periodic axes among the first ``dim``."""
        return tuple(a for a in range(dim) if self.intervals()[a] is not None)

    def period(self, dim: int) -> NDArray[np.float64]:
        """``(3,)`` periods ``upper − lower`` (m); ``0.0`` on the axes that are not periodic."""
        out = np.zeros(3)
        for a in self.axes(dim):
            lo, hi = self.intervals()[a]
            out[a] = float(hi) - float(lo)
        return out

    def lower(self, dim: int) -> NDArray[np.float64]:
        """``(3,)`` lower ends (m); ``0.0`` on the axes that are not periodic."""
        out = np.zeros(3)
        for a in self.axes(dim):
            out[a] = float(self.intervals()[a][0])
        return out

    def wrap(self, x: NDArray[np.float64]) -> None:
        """Move positions ``x (n, d)`` into ``[lower, upper)`` along every periodic axis, in place:
        ``x_a ← lower_a + (x_a − lower_a) mod L_a``."""
        dim = x.shape[1]
        lo, period = self.lower(dim), self.period(dim)
        for a in self.axes(dim):
            col = x[:, a]
            out = (col < lo[a]) | (col >= lo[a] + period[a])
            if out.any():
                wrapped = lo[a] + np.mod(col[out] - lo[a], period[a])
                # mod may round up to exactly L for a tiny negative offset: that is lower again
                wrapped[wrapped >= lo[a] + period[a]] = lo[a]
                col[out] = wrapped

    def problems(self, dim: int) -> list[str]:
        """What is wrong with the description itself for a ``dim``-dimensional domain."""
        out: list[str] = []
        for name, iv in zip("xyz", self.intervals()):
            if iv is None:
                continue
            if "xyz".index(name) >= dim:
                out.append(f"periodic axis {name} given but the domain is {dim}D; drop {name}=")
                continue
            try:
                lo, hi = (float(v) for v in iv)
            except (TypeError, ValueError):
                out.append(f"periodic {name} must be (lower, upper) in metres, got {iv!r}")
                continue
            if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
                out.append(f"periodic {name} = {iv!r}: give (lower, upper) with upper > lower, both finite")
        if not any(iv is not None for iv in self.intervals()):
            out.append("Periodic() names no axis: give x=(lower, upper) and/or y=, z=, or leave periodic unset")
        return out

    def identity(self) -> dict[str, Any]:
        """The intervals as plain lists (for a run's identity and summary)."""
        return {name: (None if iv is None else [float(iv[0]), float(iv[1])])
                for name, iv in zip("xyz", self.intervals())}


def kernel_period(periodic: Periodic | None, dim: int) -> tuple[float, float, float]:
    """The periods the kernels take (three floats, m): :data:`NO_PERIOD` without ``periodic``."""
    return NO_PERIOD if periodic is None else as_period(periodic.period(dim))


def as_period(period: ArrayLike | None) -> tuple[float, float, float]:
    """A kernel's ``period`` (three floats, m) from ``None`` (no periodic axis: zeros) or one
    period per axis (1 to 3 values, ``0`` for an axis that is not periodic)."""
    if period is None:
        return NO_PERIOD
    p = np.asarray(period, dtype=np.float64).ravel()
    if not 1 <= p.size <= 3 or not (np.isfinite(p).all() and (p >= 0).all()):
        raise ValueError(f"period must hold 1 to 3 non-negative finite periods (0: not periodic), got {period!r}")
    out = np.zeros(3)
    out[: p.size] = p
    return (float(out[0]), float(out[1]), float(out[2]))


def minimum_image(d: NDArray[np.float64], period: NDArray[np.float64]) -> NDArray[np.float64]:
    """Offsets ``d (..., dim)`` mapped to their minimum image (numpy reference of the kernels'
    :func:`mlsgalerkin.pairs.pair_offset`): ``d_a − L_a ⌊d_a/L_a + ½⌋`` on the axes with
    ``period[a] > 0`` (m), the rest unchanged. Returns a new array."""
    out = np.array(d, dtype=np.float64, copy=True)
    for a in range(out.shape[-1]):
        if period[a] > 0.0:
            out[..., a] -= period[a] * np.floor(out[..., a] / period[a] + 0.5)
    return out
