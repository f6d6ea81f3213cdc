r"""Rigid walls as penalty surfaces: the :class:`PenaltyWalls` effect, and the wall force sensors.

A :class:`~mlsgalerkin.fluid.bodies.WallBody` may carry a
:class:`~mlsgalerkin.contact.surface.ContactSurface` (``surface=``; ``wall_box(...,
surface=True)`` adds a tank's inner surface), alone or with its wall particles. Every force
evaluation, for every such wall, the fluid particles are slave nodes of a node-to-surface
penalty contact against the wall's surface (rigid master, ``m* = M_s``; the kernel and its
formulas are :mod:`mlsgalerkin.contact.penalty`, called through the one
:class:`~mlsgalerkin.contact.law.PenaltyLaw` shared with the interactions):

.. math::

    g = (\mathbf x_s - \mathbf x_c)\cdot\mathbf n - g_0,\qquad
    \mathbf f_s = \max\big(-k g - c\,\dot g,\ 0\big)\,\mathbf n \quad (-r < g < 0),\qquad
    k = \alpha\,\frac{M_s}{\Delta t_{ref}^2},\quad c = 2\zeta\sqrt{k M_s},

added to the nodal force of each fluid particle ``s`` (stage ``force``; the reaction ``−f_s`` on
the rigid wall is the force sensor below). Defaults: contact
thickness ``g0 = Δx/2`` (a lattice particle next to a wall starts at ``g = 0``), reach
``r = Δx`` (a particle up to half a spacing behind the surface is still pushed out; deeper,
it is on the far side), ``α = 0.1``, ``ζ = 0.03``. The wall surface follows the wall's
prescribed motion (the solver moves its nodes; ``ġ`` uses the wall's velocity).

**Walls need their particles.** The penalty keeps particles out of a wall; it does not replace
the wall particles (:class:`~mlsgalerkin.fluid.walls.Walls`), which close the fluid's nodal
Galerkin sums at the wall. Without them the two particle rows next to the wall carry the
boundary term of the pressure, about ``−1.5 pΔx`` and ``+0.5 pΔx`` per particle for linear MLS,
which a force on the touching particle alone cannot balance: a hydrostatic column on a
surface-only floor settles with its near-wall pressure wrong by tens of per cent of ``ρgH``
(measured in ``docs/theory/contact.md``). So list both, ``Walls()`` and ``PenaltyWalls()``, on
``wall_box(..., surface=True)``; a wall that is only a surface (``layers=0``) is for obstacles
that spray touches briefly, and :class:`SurfaceOnlyWallWarning` says so at set-up.

**Reference time step.** ``Δt_ref`` is fixed at the first force evaluation (``t = 0``) as
``safety · min`` of the other listed effects' time-step limits (capped by ``dt_max``): the
fluid's first stable step (the acoustic limit of the pressure model, in practice), unless
given (``dt_ref=``). It is checkpointed, so a restart continues with the same stiffness, bit
for bit. The effect's time-step limit is the constant
:func:`~mlsgalerkin.contact.penalty.rigid_time_step` for up to ``d`` contacts per particle
(``≈ 2.2 Δt_ref`` in 2D): it binds only if the step grows to twice the reference step.

**Force sensors.** The reaction on each wall body, ``F = −Σ f_s`` (N/m in 2D, N in 3D), and
its moment about ``moment_about`` (N·m/m in 2D; a vector in 3D; default the origin) are
time-series columns ``wall_force_x_<body>``, ``wall_force_y_<body>`` (``_z_`` in 3D),
``wall_moment_<body>`` (2D) or ``wall_moment_x|y|z_<body>`` (3D), with ``penalty_contacts``
(active contact pairs over all walls), ``penalty_max_penetration_dx`` (the deepest
``−g`` in particle spacings) and ``penalty_energy`` (the elastic energy of the active contact
springs, ``½ Σ k g²``, J per unit depth in 2D: a part of the energy balance). ``summary.json`` keeps per wall the peak force and when it
occurred, and the deepest penetration of the run.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from mlsgalerkin.contact.law import PenaltyLaw
from mlsgalerkin.contact.penalty import DEFAULT_ALPHA, DEFAULT_DAMPING, DEFAULT_FEATURE_ANGLE, check_penalty_parameters
from mlsgalerkin.fluid.bodies import FluidBody, WallBody
from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState

__all__ = ["PenaltyWalls", "SurfaceOnlyWallWarning", "sensor_columns"]


class SurfaceOnlyWallWarning(UserWarning):
    """A wall body of a ``PenaltyWalls`` scene has a penalty surface but no wall particles: the
    fluid's pressure next to it is wrong wherever the fluid rests on it (module docstring)."""


#: How deep behind a wall surface (in particle spacings) the check before step 1 looks for fluid.
START_CHECK_DEPTH = 10.0


def sensor_columns(body: str, dim: int) -> list[str]:
    """The time-series columns of the force sensor of wall ``body``."""
    axes = "xyz"[:dim]
    moment = [f"wall_moment_{body}"] if dim == 2 else [f"wall_moment_{a}_{body}" for a in "xyz"]
    return [f"wall_force_{a}_{body}" for a in axes] + moment


class PenaltyWalls(Effect):
    """Penalty contact of the fluid particles with every wall body that has a surface, and the
    force sensors of those walls (module docstring).

    Parameters
    ----------
    alpha : float
        Stiffness factor ``(ω Δt_ref)²`` (–), default 0.1.
    damping : float
        Damping ratio ζ of the contact (fraction of critical, –), default 0.03.
    thickness : float, optional
        Contact thickness ``g0`` (m); default half the fluid spacing.
    reach : float, optional
        How deep behind the surface a particle is still pushed out, counted from ``g0`` (m);
        default twice the thickness (one spacing).
    dt_ref : float, optional
        Reference time step of the stiffness (s); default the fluid's first stable step.
    feature_angle : float
        Facets closer than this (degrees) act as one smooth surface; default 30.
    moment_about : (d,) point or dict of body name to point, optional
        Where the moment on each wall is taken (m); default the origin.

    >>> PenaltyWalls()
    PenaltyWalls(alpha=0.1, damping=0.03, thickness=None, reach=None, dt_ref=None, feature_angle=30.0, moment_about=None)
    """

    name = "penalty_walls"
    stages = ("force",)
    reads = ("positions", "velocity", "mass")
    provides = ("wall_surface_contact",)

    def __init__(self, alpha: float = DEFAULT_ALPHA, damping: float = DEFAULT_DAMPING, thickness: float | None = None,
                 reach: float | None = None, dt_ref: float | None = None, feature_angle: float = DEFAULT_FEATURE_ANGLE,
                 moment_about: ArrayLike | dict[str, ArrayLike] | None = None) -> None:
        self.alpha, self.damping = alpha, damping
        self.thickness, self.reach, self.dt_ref = thickness, reach, dt_ref
        self.feature_angle = feature_angle
        self.moment_about = moment_about
        #: The contact law (lengths resolved with the fluid's spacing at set-up; ``None`` before).
        self.law: PenaltyLaw | None = None
        self._walls: list[str] = []
        self._reset_records()

    @property
    def _dt_ref(self) -> float | None:
        """The reference step in use: the law's once set up, else the one given."""
        return self.law.dt_ref if self.law is not None else self.dt_ref

    def _reset_records(self) -> None:
        self.records: dict[str, dict[str, Any]] = {}
        self.max_penetration = 0.0
        self.time_of_max_penetration: float | None = None
        self.max_contacts = 0

    def __repr__(self) -> str:
        about = self.moment_about
        if isinstance(about, dict):
            about = {k: np.asarray(v, dtype=float).tolist() for k, v in sorted(about.items())}
        elif about is not None:
            about = np.asarray(about, dtype=float).tolist()
        return (f"PenaltyWalls(alpha={self.alpha!r}, damping={self.damping!r}, thickness={self.thickness!r}, "
                f"reach={self.reach!r}, dt_ref={self.dt_ref!r}, feature_angle={self.feature_angle!r}, "
                f"moment_about={about!r})")

    # ------------------------------------------------------------------ validation
    def check(self, ctx: EffectContext) -> list[str]:
        out = check_penalty_parameters("PenaltyWalls", self.alpha, self.damping, self.thickness, self.reach,
                                       self.feature_angle, self.dt_ref)
        walls = [w for w in ctx.bodies_of(WallBody) if w.surface is not None]
        if not walls:
            out.append("PenaltyWalls: no wall body has a penalty surface; give one a surface (wall_box(..., "
                       "surface=True), or WallBody(..., surface=ContactSurface.tank(...))) or remove PenaltyWalls")
        for w in walls:
            if w.surface.dim != ctx.dim:
                out.append(f"PenaltyWalls: the surface of wall body {w.name!r} is {w.surface.dim}D but the scene is "
                           f"{ctx.dim}D")
        names = {w.name for w in walls}
        about = self.moment_about
        points = about.items() if isinstance(about, dict) else ([("all walls", about)] if about is not None else [])
        for key, point in points:
            if isinstance(about, dict) and key not in names:
                out.append(f"PenaltyWalls: moment_about names {key!r}, which is not a wall body with a surface "
                           f"({sorted(names)})")
            p = np.asarray(point, dtype=float) if np.ndim(point) else np.zeros(0)
            if p.shape != (ctx.dim,) or not np.all(np.isfinite(p)):
                out.append(f"PenaltyWalls: moment_about for {key} must be a finite ({ctx.dim},) point, got {point!r}")
        if out:
            return out
        fluids = ctx.bodies_of(FluidBody)
        if fluids and walls:
            out.extend(self._starting_penetrations(fluids, walls))
        return out

    def _starting_penetrations(self, fluids: list[FluidBody], walls: list[WallBody]) -> list[str]:
        """Fluid particles that start behind a wall surface (up to :data:`START_CHECK_DEPTH`
        spacings deep): within the reach the full penalty force would throw them out at the
        first step, deeper they would stay on the far side for good."""
        out = []
        dx = fluids[0].spacing
        g0, _ = self._lengths(dx)
        x = np.concatenate([b.positions for b in fluids])
        probe = PenaltyLaw(thickness=g0, reach=g0 + START_CHECK_DEPTH * dx, feature_angle=self.feature_angle,
                           dt_ref=1.0)   # only the gaps are read
        for w in walls:
            res = probe.forces(x, np.zeros_like(x), 1.0, w.surface.nodes, None, None, w.surface.facets)
            behind = np.flatnonzero(res.gaps < -g0 - 1e-9 * dx)
            if behind.size:
                k = int(behind[np.argmin(res.gaps[behind])])
                out.append(f"PenaltyWalls: {behind.size} fluid particles start behind the penalty surface of wall "
                           f"body {w.name!r} (the deepest at {np.round(x[k], 6).tolist()}, "
                           f"{(-res.gaps[k] - g0) / dx:.2f} spacings behind): the fluid reaches into the wall; place "
                           "it in front of the surface, half a spacing away as lattice() and wall_box() do")
        return out

    def _lengths(self, dx: float) -> tuple[float, float]:
        g0 = 0.5 * dx if self.thickness is None else float(self.thickness)
        reach = (2.0 * g0 if g0 > 0 else dx) if self.reach is None else float(self.reach)
        return g0, reach

    # ------------------------------------------------------------------ set-up
    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        walls = [w for w in ctx.bodies_of(WallBody) if w.surface is not None]
        self._walls = [w.name for w in walls]
        bare = [w.name for w in walls if w.n == 0]
        if bare:
            warnings.warn(
                f"PenaltyWalls: wall bodies {bare} are only a penalty surface, without wall particles: the fluid's "
                "Galerkin sums are not closed there, and where the fluid rests on such a wall its pressure is wrong "
                "(a hydrostatic column on a surface-only floor: tens of per cent of rho g H, docs/theory/contact.md). "
                "For walls that hold fluid use wall_box(..., layers=3, surface=True) with Walls() and PenaltyWalls()",
                SurfaceOnlyWallWarning, stacklevel=2)
        self._g0, self._reach = self._lengths(state.spacing)
        # a reference step fixed by an earlier run of this effect is kept, as it always was
        self.law = PenaltyLaw(thickness=self._g0, reach=self._reach, alpha=self.alpha, damping=self.damping,
                              feature_angle=self.feature_angle, dt_ref=self._dt_ref)
        d = state.dim
        about = self.moment_about
        self._centre = {}
        for name in self._walls:
            point = about.get(name) if isinstance(about, dict) else about
            self._centre[name] = np.zeros(d) if point is None else np.asarray(point, dtype=float)
        self._others = [e for e in ctx.effects if e is not self]
        self._safety, self._dt_max = ctx.safety, ctx.dt_max
        self._spacing = state.spacing
        self._dim = d
        for name in self._walls:
            for col in sensor_columns(name, d):
                state.sensors[col] = 0.0
        state.sensors["penalty_contacts"] = 0
        state.sensors["penalty_max_penetration_dx"] = 0.0
        state.sensors["penalty_energy"] = 0.0
        self._reset_records()
        self.records = {name: {"peak_force": 0.0, "time_of_peak_force_s": None, "peak_force_vector": [0.0] * d,
                               "max_abs_moment": 0.0} for name in self._walls}

    def _reference_step(self, s: FluidState) -> float:
        """``safety · min`` of the other effects' limits (and ``dt_max``) now."""
        dt = self._safety * min([e.time_step_limit(s) for e in self._others] + [math.inf])
        if self._dt_max is not None:
            dt = min(dt, self._dt_max)
        return dt

    # ------------------------------------------------------------------ the force stage
    def force(self, s: FluidState) -> None:
        law = self.law
        law.fix_reference_step(lambda: self._reference_step(s), lambda dt: (
            "PenaltyWalls: no reference time step for the penalty stiffness (no other effect limits the step, got "
            f"{dt!r}); give PenaltyWalls(dt_ref=...) or the fluid scheme's dt_max"))
        f = s.fluid
        x, v, M = s.x[f], s.v[f], s.M[f]
        contacts = 0
        deepest = 0.0
        law.begin()
        for name in self._walls:
            surf = s.wall_surfaces[name]
            res = law.forces(x, v, M, surf.x, surf.v, None, surf.facets, centre=self._centre[name])
            s.force[f] += res.slave_forces
            cols = sensor_columns(name, self._dim)
            for a in range(self._dim):
                s.sensors[cols[a]] = float(res.total_force[a])
            moments = [res.moment] if self._dim == 2 else list(res.moment)
            for c, m in zip(cols[self._dim:], moments):
                s.sensors[c] = float(m)
            rec = self.records[name]
            magnitude = float(np.sqrt(res.total_force @ res.total_force))
            if magnitude > rec["peak_force"]:
                rec["peak_force"], rec["time_of_peak_force_s"] = magnitude, float(s.t)
                rec["peak_force_vector"] = res.total_force.tolist()
            rec["max_abs_moment"] = max(rec["max_abs_moment"], float(np.max(np.abs(moments))))
            contacts += res.contacts
            deepest = max(deepest, res.max_penetration)
        s.sensors["penalty_contacts"] = int(contacts)
        s.sensors["penalty_energy"] = law.energy
        s.sensors["penalty_max_penetration_dx"] = deepest / self._spacing
        self.max_contacts = max(self.max_contacts, contacts)
        if deepest > self.max_penetration:
            self.max_penetration, self.time_of_max_penetration = deepest, float(s.t)

    def time_step_limit(self, s: FluidState) -> float:
        return self.law.time_step_limit(s.dim) if self.law is not None else math.inf

    # ------------------------------------------------------------------ report and restart
    def summary(self) -> dict[str, Any]:
        if self._dt_ref is None:
            return {}
        return {
            "alpha": self.alpha, "damping": self.damping, "thickness_m": self._g0, "reach_m": self._reach,
            "feature_angle_deg": self.feature_angle, "dt_ref_s": self._dt_ref,
            "stiffness_per_kg_N_per_m_kg": self.alpha / self._dt_ref**2,
            "time_step_limit_s": self.law.time_step_limit(self._dim),
            "max_penetration_m": self.max_penetration, "max_penetration_dx": self.max_penetration / self._spacing,
            "time_of_max_penetration_s": self.time_of_max_penetration, "max_active_contacts": self.max_contacts,
            "walls": self.records,
        }

    def state_dict(self) -> dict[str, Any]:
        return {"dt_ref": self._dt_ref, "records": self.records, "max_penetration": self.max_penetration,
                "time_of_max_penetration": self.time_of_max_penetration, "max_contacts": self.max_contacts}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        if not d:
            return
        self.law.dt_ref = d["dt_ref"]
        self.records = {k: dict(v) for k, v in d["records"].items()}
        self.max_penetration = float(d["max_penetration"])
        self.time_of_max_penetration = d["time_of_max_penetration"]
        self.max_contacts = int(d["max_contacts"])

