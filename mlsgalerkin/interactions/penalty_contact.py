r""":class:`PenaltyContact`: node-to-surface penalty contact between two bodies of a scene.

The *slave* body exposes its nodes (a :class:`~mlsgalerkin.dynamics.Surface` with no
segments: the particles of a fluid body), the *master* body a surface with segments (2D) or
triangles (3D) — a structure's boundary. Once per step, between the solvers'
``begin_step`` and ``end_step``, :meth:`PenaltyContact.exchange` reads both surfaces at
``t + Δt``, computes the penalty forces with its :class:`~mlsgalerkin.contact.law.PenaltyLaw`
(:func:`~mlsgalerkin.contact.penalty.penalty_forces`) and adds them to the slave nodes and,
equal and opposite, to the master nodes (``add_surface_forces``). A master whose
``Surface.masses`` is ``None`` is rigid (``m* = m_s``).

**Reference time step.** The stiffness is ``k = α m*/Δt_ref²``. ``dt_ref`` may be given; by
default it is fixed at the first exchange as the smaller of the two solvers' stable steps
(the step the run started with) and kept for the rest of the run: it is part of
:meth:`PenaltyContact.state_dict`, so a restarted run uses the same stiffness and continues bit
for bit. The interaction's time-step limit (:meth:`PenaltyContact.stable_time_step`) is the
constant bound for a slave with up to ``d`` contacts and the bound of the master nodes touched at
the last exchange (:mod:`mlsgalerkin.contact.penalty`).

>>> contact = PenaltyContact("water", "plate", thickness=0.005)   # particles of spacing 0.01 m
>>> contact.reach, contact.alpha, contact.damping
(0.01, 0.1, 0.03)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from mlsgalerkin.contact.law import PenaltyLaw
from mlsgalerkin.contact.penalty import DEFAULT_ALPHA, DEFAULT_DAMPING, DEFAULT_FEATURE_ANGLE, check_penalty_parameters
from mlsgalerkin.dynamics import Interaction, SceneView, Solver

__all__ = ["PenaltyContact"]


class PenaltyContact(Interaction):
    """Penalty contact of the nodes of body ``slave`` against the surface of body ``master``.

    Parameters
    ----------
    slave, master : str
        Body names (``first`` and ``second`` of the interaction).
    thickness : float
        Contact thickness ``g0`` (m): half the particle spacing for particles, 0 for nodes.
    reach : float, optional
        How far from ``g0`` toward and behind the master surface a slave is still pushed out
        (m; active if ``−reach < g < 0``); default ``2 g0``, required when ``g0 = 0``. Must
        exceed ``g0``.
    alpha : float
        Stiffness factor ``(ω Δt_ref)²`` (–), default 0.1.
    damping : float
        Damping ratio ζ of the contact spring (fraction of critical, –), default 0.03.
    dt_ref : float, optional
        Reference time step of the stiffness (s); default: fixed at the first exchange.
    feature_angle : float
        Facets whose normals differ by less than this (degrees) act as one smooth surface.
    moment_about : (d,) array, optional
        Point about which the moment on the master is reported (default the origin).
    name : str
        Key of the interaction in ``summary.json``.
    """

    def __init__(self, slave: str, master: str, *, thickness: float = 0.0, reach: float | None = None,
                 alpha: float = DEFAULT_ALPHA, damping: float = DEFAULT_DAMPING, dt_ref: float | None = None,
                 feature_angle: float = DEFAULT_FEATURE_ANGLE, moment_about: ArrayLike | None = None,
                 name: str = "contact") -> None:
        self.first, self.second, self.name = slave, master, name
        if reach is None and isinstance(thickness, (int, float)) and thickness > 0:
            reach = 2.0 * thickness  # nodes without a thickness have no natural reach: asked for
        #: The contact law: parameters, the reference step once fixed, the stored energy.
        self.law = PenaltyLaw(thickness=thickness, reach=reach, alpha=alpha, damping=damping,
                              feature_angle=feature_angle, dt_ref=dt_ref)
        self.dt_ref = dt_ref
        self.moment_about = None if moment_about is None else np.asarray(moment_about, dtype=float)
        self._rigid: bool | None = None
        self._dim: int | None = None
        self._last_stable = math.inf
        self.exchanges = 0
        self.peak_force = 0.0
        self.time_of_peak_force: float | None = None
        self.max_penetration = 0.0
        self.max_active = 0
        self.last: dict[str, Any] = {}

    # the parameters, as the law holds them (read-only: give them to the constructor)
    thickness = property(lambda self: self.law.thickness, doc="Contact thickness ``g0`` (m).")
    reach = property(lambda self: self.law.reach, doc="Reach behind ``g0`` (m).")
    alpha = property(lambda self: self.law.alpha, doc="Stiffness factor (–).")
    damping = property(lambda self: self.law.damping, doc="Damping ratio (–).")
    feature_angle = property(lambda self: self.law.feature_angle, doc="Feature angle (degrees).")

    @property
    def energy(self) -> float:
        """Elastic energy of the contact springs at the last exchange (J, per m in 2D)."""
        return self.law.energy

    @property
    def slave(self) -> str:
        return self.first

    @property
    def master(self) -> str:
        return self.second

    def __repr__(self) -> str:
        about = None if self.moment_about is None else self.moment_about.tolist()
        return (f"PenaltyContact(name={self.name!r}, slave={self.first!r}, master={self.second!r}, "
                f"thickness={self.thickness!r}, reach={self.reach!r}, alpha={self.alpha!r}, damping={self.damping!r}, "
                f"dt_ref={self.dt_ref!r}, feature_angle={self.feature_angle!r}, moment_about={about!r})")

    # ------------------------------------------------------------------ validation
    def problems(self, scene: SceneView) -> list[str]:
        owner = f"PenaltyContact {self.name!r}"
        out = super().problems(scene)
        out += check_penalty_parameters(owner, self.alpha, self.damping, self.thickness, self.reach,
                                        self.feature_angle, self.dt_ref)
        if self.reach is None:
            out.append(f"{owner}: give reach= (m), how deep behind the surface a slave is still pushed out")
        if self.first == self.second:
            out.append(f"{owner}: slave and master are the same body {self.first!r}; self-contact is not supported")
        if self.moment_about is not None and scene.dim and self.moment_about.shape != (scene.dim,):
            out.append(f"{owner}: moment_about must be a ({scene.dim},) point, got shape {self.moment_about.shape}")
        return out

    # ------------------------------------------------------------------ per step
    def exchange(self, t: float, first: Solver, second: Solver) -> None:
        """Penalty forces at time ``t`` on the slave nodes and the master nodes."""
        owner = f"PenaltyContact {self.name!r}"
        sl, ms = first.surface(self.first), second.surface(self.second)
        if ms.segments.shape[0] == 0:
            raise ValueError(f"{owner}: the master body {self.second!r} exposes no segments to touch; the master must "
                             "be a body with a surface (its solver's surface() must return segments)")
        if sl.masses is None:
            raise ValueError(f"{owner}: the slave body {self.first!r} gives no nodal masses; the stiffness needs them")
        self.law.fix_reference_step(
            lambda: min(first.stable_time_step(), second.stable_time_step()),
            lambda dt: f"{owner}: no reference time step (the solvers of {self.first!r} and {self.second!r} report "
                       f"{dt!r}); give dt_ref=")
        d = sl.positions.shape[1]
        self._dim, self._rigid = d, ms.masses is None
        self.law.begin()
        res = self.law.forces(sl.positions, sl.velocities, sl.masses, ms.positions, ms.velocities, ms.masses,
                              ms.segments, centre=self.moment_about)
        first.add_surface_forces(self.first, res.slave_forces)
        second.add_surface_forces(self.second, res.master_forces)
        self.exchanges += 1
        self._last_stable = res.stable_dt
        force = float(np.sqrt(res.total_force @ res.total_force))
        if force > self.peak_force:
            self.peak_force, self.time_of_peak_force = force, float(t)
        self.max_penetration = max(self.max_penetration, res.max_penetration)
        self.max_active = max(self.max_active, res.contacts)
        moment = res.moment if d == 2 else np.asarray(res.moment).tolist()
        self.last = {"t": float(t), "force": res.total_force.tolist(), "moment": moment, "contacts": res.contacts,
                     "max_penetration": res.max_penetration}

    def stable_time_step(self) -> float:
        """Constant bound for a slave with up to ``d`` contacts, and the bound of the master nodes
        touched at the last exchange (s); ``inf`` before the first exchange."""
        if self.law.dt_ref is None or self._dim is None:
            return math.inf
        kappa = 1 if self._rigid else 2
        return min(self.law.time_step_limit(kappa * self._dim), self._last_stable)

    # ------------------------------------------------------------------ restart and report
    def observables(self) -> dict[str, float]:
        """``<name>_energy``: the elastic energy of the active contact springs at the last
        exchange, ``½ Σ k g²`` (J, per unit depth in 2D)."""
        return {f"{self.name}_energy": self.energy}

    def state_dict(self) -> dict[str, Any]:
        return {"dt_ref": self.law.dt_ref, "rigid": self._rigid, "dim": self._dim, "energy": self.energy,
                "last_stable_dt": None if math.isinf(self._last_stable) else self._last_stable,
                "exchanges": self.exchanges, "peak_force": self.peak_force, "time_of_peak_force": self.time_of_peak_force,
                "max_penetration": self.max_penetration, "max_active": self.max_active, "last": self.last}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.law.dt_ref, self._rigid, self._dim = d["dt_ref"], d["rigid"], d["dim"]
        self._last_stable = math.inf if d["last_stable_dt"] is None else float(d["last_stable_dt"])
        self.exchanges, self.peak_force = int(d["exchanges"]), float(d["peak_force"])
        self.time_of_peak_force, self.max_penetration = d["time_of_peak_force"], float(d["max_penetration"])
        self.max_active, self.last = int(d["max_active"]), dict(d["last"])
        self.law.energy = float(d.get("energy", 0.0))   # checkpoints written before the column existed

    def summary(self) -> dict[str, Any]:
        return {
            "slave": self.first, "master": self.second, "alpha": self.alpha, "damping": self.damping,
            "thickness_m": self.thickness, "reach_m": self.reach, "dt_ref_s": self.law.dt_ref,
            "master_rigid": self._rigid, "exchanges": self.exchanges,
            "peak_force_N": self.peak_force, "time_of_peak_force_s": self.time_of_peak_force,
            "max_penetration_m": self.max_penetration, "active_contacts_max": self.max_active,
            "last": self.last,
        }
