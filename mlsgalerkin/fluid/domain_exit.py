r"""Fluid particles that leave the domain are taken out of the run.

A splash thrown over the end wall of an open tank falls forever: nothing can bring it back, yet
it keeps accelerating, and its speed sets the acoustic time step :math:`h/(c + |v|)`, forces a
neighbour rebuild at every step, drives the Mach check and dominates the kinetic energy. (A dam
break on a clamped beam at its defaults, 4 s: four particles leave the tank at about 1.2 s and
fall 22 m at up to 33 m/s; the step shrinks from 5.1·10⁻⁵ s to 3.2·10⁻⁵ s, 83 322 of the 93 892
steps rebuild the neighbour table, the Mach check reads 1.18 and the kinetic energy ends at
28 J/m. Taken out, seven particles leave between 0.44 and 2.08 s, 0.56 % of the mass; the step
stays at 5.5·10⁻⁵ s, 30 242 of 72 390 steps rebuild, the Mach check reads 0.25, the kinetic
energy ends at 0.07 J/m, and the run takes 1050 s instead of 3213 s on one thread. The run is
the same bit for bit until the first exit, and the beam's period moves from 0.6062 to 0.6061 s.)

**The domain** is the bounding box of every particle at the start (fluid and walls), widened by
a margin :math:`m` on each side, with no bound along a periodic axis or on the side gravity
points away from (a splash that rises falls back):

.. math:: \mathbf l = \min_i \mathbf x_i - m, \qquad \mathbf u = \max_i \mathbf x_i + m,
          \qquad m = 2\,\max_i r_i,

:math:`r_i` the neighbour search radius (kernel support plus skin), so that a particle outside
is more than a whole support away from every wall particle and from every fluid particle still
inside: no force can reach it, and it can only keep flying away. A scene without wall particles
has no domain (a fluid alone, e.g. a falling drop, keeps all its particles).

**Walls that move** (a hinged beam leaning out, a floating body) widen it: at every step the
bounds on each bounded side are the starting box's or those of the wall particles where they are
now, widened by the same margin, whichever reaches farther. Water riding on a beam that leans out
of the starting box stays in the run; water left behind when the wall returns is taken out. The
domain depends on the start and the present only, so a restart rebuilds it exactly. (The
`beam_on_spring` dam break at its default spacing: the beam leans out to 14°, and 94 particles on
it, 2.9 % of the water, were taken out at x = 3.345 m although they rode on the beam.)

**Taken out** (:meth:`DomainExit.after_step`, at the end of every step): a fluid particle past a
bound is marked in the state's ``extra["outside"]`` (bool ``(n,)``, the wall rows never) with its
time in ``extra["exit_time"]`` (s; NaN inside) and stays where it left, with ``v = 0``,
``a = 0`` and ``dρ/dt = 0``, so it no longer moves, sets no time step and counts in no kinetic
energy. The neighbour search and the penalty contact see it far away
(:meth:`DomainExit.search_positions`): no other particle has it as a neighbour, it has none, and no
structure touches it (a particle held still where a beam later swings would hold the beam). The run checks (volume, pairs, fallbacks) leave
it out; its mass stays in ``total_mass`` (nothing is destroyed), and the time-series column
``particles_outside`` and the summary (``fluid.domain_exit``) count it. A warning says when the
first particles leave.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.fluid.state import FluidState

__all__ = [
    "EXIT_TIME",
    "MARGIN_RADII",
    "OUTSIDE",
    "DomainExit",
    "ParticlesLeftDomainWarning",
    "mark_and_hold",
    "mark_and_hold_reference",
    "still_in_run",
]

#: The state's ``extra`` array that marks the fluid particles taken out of the run (bool ``(n,)``).
OUTSIDE = "outside"
#: The state's ``extra`` array of the time each particle left the domain (s; NaN inside).
EXIT_TIME = "exit_time"
#: The margin around the particles' starting bounding box, in neighbour search radii.
MARGIN_RADII = 2.0
#: How far past the domain (in search radii) the neighbour search puts the particles taken out,
#: and how far apart: no two of them, and none of them and a particle inside, are neighbours.
_PARK_RADII = 4.0


def still_in_run(s: FluidState) -> NDArray[np.bool_]:
    """The mask ``(n_fluid,)`` of the fluid particles not taken out of the run (all of them when no
    :class:`DomainExit` marks any)."""
    out = s.extra.get(OUTSIDE)
    return ~out[: s.n_fluid] if out is not None else np.ones(s.n_fluid, dtype=bool)


@numba.njit(cache=True)
def mark_and_hold(x, n_fluid, lower, upper, out, v, a, drho):
    """Mark the fluid rows ``< n_fluid`` of ``x (n, d)`` past ``lower``/``upper (d,)`` in ``out``
    (bool ``(n,)``), and zero ``v``, ``a`` ``(n, d)`` and ``drho (n,)`` on every marked row.
    Returns the rows marked now (int64). One pass over the fluid, no temporaries."""
    new = np.empty(n_fluid, dtype=np.int64)
    count = 0
    dim = x.shape[1]
    for i in range(n_fluid):
        if not out[i]:
            for k in range(dim):
                if x[i, k] < lower[k] or x[i, k] > upper[k]:
                    out[i] = True
                    new[count] = i
                    count += 1
                    break
        if out[i]:
            for k in range(dim):
                v[i, k] = 0.0
                a[i, k] = 0.0
            drho[i] = 0.0
    return new[:count]


def mark_and_hold_reference(x, n_fluid, lower, upper, out, v, a, drho):
    """numpy reference of :func:`mark_and_hold`."""
    f = slice(0, n_fluid)
    past = np.any(x[f] < lower, axis=1) | np.any(x[f] > upper, axis=1)
    new = np.flatnonzero(past & ~out[f])
    out[new] = True
    v[out] = 0.0
    a[out] = 0.0
    drho[out] = 0.0
    return new


class ParticlesLeftDomainWarning(UserWarning):
    """Fluid particles left the domain and were taken out of the run."""


class DomainExit:
    """The domain of a fluid run and what happens to the fluid particles that leave it
    (module docstring). ``lower``, ``upper`` ``(d,)`` (m; ``±inf`` where unbounded),
    ``radius`` (m) the largest neighbour search radius."""

    def __init__(self, lower: NDArray[np.float64], upper: NDArray[np.float64], radius: float) -> None:
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.start_lower, self.start_upper = self.lower.copy(), self.upper.copy()
        self.radius = float(radius)
        finite = np.isfinite(self.lower)
        if not finite.any():
            raise ValueError("DomainExit needs a finite lower bound along at least one axis")
        #: the axis and the coordinate below which the search parks the particles taken out
        self._park_axis = int(np.flatnonzero(finite)[0])
        self._warned = False

    @classmethod
    def around(cls, x: NDArray[np.float64], radius: float, gravity: NDArray[np.float64] | None,
               periodic_axes: tuple[int, ...] = ()) -> DomainExit | None:
        """The domain around the particles at ``x (n, d)`` (m) with margin
        ``MARGIN_RADII · radius`` (m); no bound along ``periodic_axes`` or on the side
        ``gravity (d,)`` (m/s²) points away from. ``None`` when no axis is bounded below."""
        x = np.asarray(x, dtype=float)
        margin = MARGIN_RADII * float(radius)
        lower = x.min(axis=0) - margin
        upper = x.max(axis=0) + margin
        if gravity is not None:
            g = np.asarray(gravity, dtype=float)
            upper[g < 0.0] = np.inf
            lower[g > 0.0] = -np.inf
        for a in periodic_axes:
            lower[a], upper[a] = -np.inf, np.inf
        if not np.isfinite(lower).any():
            return None
        return cls(lower, upper, radius)

    def setup(self, s: FluidState) -> None:
        """Add the ``outside`` and ``exit_time`` arrays to the state (kept when a checkpoint
        restored them already)."""
        if OUTSIDE not in s.extra or np.asarray(s.extra[OUTSIDE]).shape != (s.n,):
            s.extra[OUTSIDE] = np.zeros(s.n, dtype=bool)
            s.extra[EXIT_TIME] = np.full(s.n, np.nan)

    def follow_walls(self, walls: NDArray[np.float64]) -> None:
        """The bounds of the starting box widened to the wall particles at ``walls (n_w, d)`` (m)
        plus the margin, on the bounded sides only (module docstring)."""
        if walls.shape[0] == 0:
            return
        margin = MARGIN_RADII * self.radius
        self.lower = np.minimum(self.start_lower, walls.min(axis=0) - margin)
        self.upper = np.maximum(self.start_upper, walls.max(axis=0) + margin)

    def after_step(self, s: FluidState) -> int:
        """Widen the bounds to the walls where they are now (:meth:`follow_walls`), mark the
        fluid particles now past a bound, then hold every marked one still (``v``, ``a``, ``dρ/dt``
        zero). Returns the number that left in this step."""
        self.follow_walls(s.x[s.n_fluid:])
        new = mark_and_hold(s.x, s.n_fluid, self.lower, self.upper, s.extra[OUTSIDE], s.v, s.a, s.drho)
        if new.size:
            s.extra[EXIT_TIME][new] = s.t
            if not self._warned:
                self._warned = True
                self._warn(s, new)
        return int(new.size)

    def search_positions(self, x: NDArray[np.float64], s: FluidState) -> NDArray[np.float64]:
        """``x (n, d)`` (m) with the particles taken out moved, for the neighbour search and the
        penalty contact only, to
        points ``_PARK_RADII`` search radii apart, that far below the domain's lower bound along
        its first bounded axis: they have no neighbours and are nobody's. ``x`` itself when no
        particle is out."""
        out = s.extra.get(OUTSIDE)
        if out is None or not out.any():
            return x
        rows = np.flatnonzero(out)
        step = _PARK_RADII * self.radius
        parked = np.array(x, dtype=float, copy=True)
        a = self._park_axis
        other = (a + 1) % x.shape[1] if x.shape[1] > 1 else a
        parked[rows, a] = self.lower[a] - step
        if other != a:
            base = float(np.min(x[:, other]))
            parked[rows, other] = base + step * np.arange(rows.size)
        else:
            parked[rows, a] = self.lower[a] - step * (1.0 + np.arange(rows.size))
        return parked

    def _warn(self, s: FluidState, new: NDArray[np.int64]) -> None:
        k = int(new[0])      # its velocity is already zero (held): the message gives where it crossed
        bounds = ", ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in zip(self.lower, self.upper))
        warnings.warn(
            f"at t = {s.t:.6g} s, {new.size} fluid particle(s) left the domain {bounds} m (the particles' starting "
            f"bounding box widened by {MARGIN_RADII:g} search radii, open above): particle {k} at "
            f"{np.round(s.x[k], 4).tolist()} m. Nothing can bring them back, so they are taken out of the run: held where they "
            "left, in no force, time step, kinetic energy or run check, their mass kept. The column particles_outside "
            "of timeseries.csv counts them and summary.json (fluid.domain_exit) reports their mass",
            ParticlesLeftDomainWarning, stacklevel=3)

    def summary(self, s: FluidState) -> dict[str, Any]:
        """Bounds, margin, and the particles taken out: count, mass (kg, per unit depth in 2D)
        and its share of the fluid's, first and last exit times (s)."""
        out = s.extra[OUTSIDE][s.fluid]
        times = s.extra[EXIT_TIME][s.fluid][out]
        mass = float(s.M[s.fluid][out].sum())
        total = float(s.M[s.fluid].sum())

        def bound(v: NDArray[np.float64]) -> list[float | None]:
            return [float(b) if math.isfinite(b) else None for b in v]

        return {
            "lower_m": bound(self.lower), "upper_m": bound(self.upper), "margin_m": MARGIN_RADII * self.radius,
            "particles_outside": int(out.sum()), "mass_outside_kg": mass,
            "mass_share_outside": mass / total if total > 0 else 0.0,
            "first_exit_s": float(times.min()) if times.size else None,
            "last_exit_s": float(times.max()) if times.size else None,
        }
