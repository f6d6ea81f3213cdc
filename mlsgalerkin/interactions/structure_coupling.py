r""":class:`StructureCoupling`: the fluid loads a structure, and the structure bounds the fluid.

A structure (any body whose solver exposes a :class:`~mlsgalerkin.dynamics.Surface` with
facets — segments in 2D, triangles in 3D: an elastic body on scikit-fem, a rigid body) meets a
fluid body in two ways, both momentum-conserving, both every step, in 2D and in 3D:

1. **Wall particles riding on the structure** (a :class:`~mlsgalerkin.fluid.bodies.WallBody`
   built by :meth:`~mlsgalerkin.fluid.bodies.WallBody.on_surface`, ``follows`` the structure).
   They stand on points spread evenly over the structure's wet surface
   (:func:`~mlsgalerkin.contact.surface.surface_points`), each point standing for a piece of
   surface about one spacing long in 2D, or a sub-triangle of about one spacing squared in 3D
   (its *footprint*), at depths ``δ`` behind it:

   .. math:: \mathbf x_w = \bar{\mathbf x}_p - \delta\,\mathbf n_p,\qquad
             \mathbf v_w = \bar{\mathbf v}_p - \delta\,\dot{\mathbf n}_p,\qquad
             \mathbf a_w = \bar{\mathbf a}_p,

   with :math:`\bar{(\cdot)}_p = \sum_a W_{pa}(\cdot)_a` the footprint mean over the surface
   nodes ``a`` and :math:`\mathbf n_p` the normal of the footprint's chord (2D) or of its
   triangle (3D). They are set at the
   exchange of every step (``t + Δt``, the structure already advanced), with the structure's
   mean velocity and acceleration over the step, so the fluid's wall treatment
   (:class:`~mlsgalerkin.fluid.walls.Walls`) sees the surface move (and, with
   ``wall_acceleration``, accelerate: ``g − a_w`` in the extrapolated wall pressure). They close
   the fluid's nodal Galerkin sums at the structure as wall particles do at a fixed wall. Their
   reaction — the nodal force of the fluid on them, :math:`\mathbf f_w = -\sum_k\sigma_k\nabla
   N_w(\mathbf x_k)V_k` (the sums over all nodes add to zero, so this is exactly what the fluid
   lost) — goes to the surface nodes after the fluid's force evaluation (:meth:`after_step`) by
   the transpose of the same map, :math:`\mathbf f_a = \sum_w W_{p(w)a}\,\mathbf f_w`.
2. **Node-to-surface penalty contact** of the fluid particles (slaves) on the structure's
   surface (master) — :class:`~mlsgalerkin.interactions.PenaltyContact`: no particle passes
   through the structure, and the contact reactions go to the structure's surface nodes.

The coupling is explicit and staggered (the structure advances with the loads of the last step,
then the fluid with the structure's new position); the loads of a step reach the structure in
the next. The time step is the fluid's and the contact's (the structure sub-cycles inside it).
With ``iterations > 1`` each step is repeated until the interface converges (the partitioned
iteration with Aitken relaxation of ``docs/theory/fsi.md`` §3): the structure then advances with
the fluid's load of the previous pass at the step's end, the riding particles take the relaxed
interface ``x̃ ← x̃ + ω(x* − x̃)``, and the step is accepted when the CRMS of ``x* − x̃`` over the
first layer falls below ``tolerance``.

>>> StructureCoupling("water", "gate", walls="gate_walls", thickness=0.001)
StructureCoupling(fluid='water', structure='gate', walls='gate_walls', wall_acceleration=0.0, iterations=1, ...)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.contact.penalty import DEFAULT_ALPHA, DEFAULT_DAMPING, DEFAULT_FEATURE_ANGLE
from mlsgalerkin.contact.surface import SurfacePoints, TrianglePoints
from mlsgalerkin.dynamics import CarriesStepEndLoad, DrivesWalls, Interaction, SceneView, Solver, Surface
from mlsgalerkin.fluid.bodies import FluidBody, WallBody
from mlsgalerkin.interactions.penalty_contact import PenaltyContact

__all__ = ["AITKEN_RANGE", "StructureCoupling", "riding_kinematics"]

#: Bounds of Aitken's relaxation factor ω.
AITKEN_RANGE = (1e-3, 1.0)

FloatArray = NDArray[np.float64]


def riding_kinematics(surface: Surface, footprints: SurfacePoints | TrianglePoints, anchors: FloatArray
                     ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Positions (m), velocities (m/s), accelerations (m/s²) and normals ``(n, d)`` of wall
    particles riding on the 2D or 3D ``surface`` at the ``anchors`` (point, depth) of
    ``footprints`` (module docstring)."""
    x, v, n, dn = footprints.kinematics(surface.positions, surface.velocities)
    point = anchors[:, 3].astype(np.int64)
    depth = anchors[:, 2:3]
    pos = x[point] - depth * n[point]
    vel = v[point] - depth * dn[point]
    acc = (footprints.average @ surface.accelerations)[point] if surface.accelerations is not None else np.zeros_like(pos)
    return pos, vel, acc, n[point]


class StructureCoupling(Interaction):
    """Fluid body ``fluid`` against structure body ``structure``: the wall particles ``walls``
    riding on it, and penalty contact (module docstring).

    Parameters
    ----------
    fluid, structure : str
        Body names (``first`` and ``second`` of the interaction).
    walls : str, optional
        A wall body built with ``WallBody.on_surface(..., follows=structure)``; without it the
        structure is a penalty surface only (the fluid's pressure next to it is then wrong
        wherever the fluid rests on it: ``docs/theory/contact.md``).
    thickness, reach, alpha, damping, dt_ref, feature_angle
        The penalty contact's parameters (:class:`~mlsgalerkin.interactions.PenaltyContact`):
        thickness ``g0`` (m, half the particle spacing), reach (m, default ``2 g0``), stiffness
        factor, damping ratio, reference step (s), feature angle (degrees).
    wall_acceleration : float
        The share (0 to 1) of the structure's acceleration the wall pressure sees. 0 by default:
        with 1 an explicit coupling diverged for the light rubber gate of ``elastic_gate`` and the
        clamped beam of ``beam_clamped``, while the heavy plate of ``hydrostatic_plate`` needed it
        (``docs/theory/fsi.md`` §2). With ``iterations > 1``, 1 is safe.
    iterations : int
        Passes of the partitioned iteration per step (1: the explicit, staggered coupling).
    tolerance : float
        Convergence of the iteration: the CRMS of the interface residual (m).
    relaxation : float
        Aitken's relaxation factor to start from (0 to 1).
    name : str
        Key in ``summary.json``.
    """

    def __init__(self, fluid: str, structure: str, *, walls: str | None = None, thickness: float = 0.0,
                 reach: float | None = None, alpha: float = DEFAULT_ALPHA, damping: float = DEFAULT_DAMPING,
                 dt_ref: float | None = None, feature_angle: float = DEFAULT_FEATURE_ANGLE,
                 wall_acceleration: float = 0.0, iterations: int = 1, tolerance: float = 1e-5,
                 relaxation: float = 0.5, name: str = "coupling") -> None:
        self.first, self.second, self.walls, self.name = fluid, structure, walls, name
        self.contact = PenaltyContact(fluid, structure, thickness=thickness, reach=reach, alpha=alpha,
                                      damping=damping, dt_ref=dt_ref, feature_angle=feature_angle,
                                      name=f"{name}_contact")
        self._anchors: FloatArray | None = None
        self._footprints: SurfacePoints | TrianglePoints | None = None
        self._previous: tuple | None = None     # wall kinematics of the last accepted step
        self._pending: tuple | None = None      # ... of this step, until it is accepted
        self.wall_acceleration = wall_acceleration
        self.iterations, self.tolerance, self.relaxation = iterations, tolerance, relaxation
        self.reaction = np.zeros(2)       # total wall-particle reaction of the last step (N; (d,): problems())
        self.contact_force = np.zeros(2)  # total contact force on the structure of the last step (N)
        self.peak_load = 0.0
        self.time_of_peak_load: float | None = None
        # partitioned iteration: the relaxed interface, the last residual, the load of the last pass
        self._guess: tuple | None = None
        self._residual: FloatArray | None = None
        self._omega = relaxation
        self._load = None
        self.crms = float("nan")
        self.passes: list[int] = []
        self.unconverged_steps = 0
        self.seconds = {"walls": 0.0, "contact": 0.0, "reaction": 0.0}

    @property
    def iterates(self) -> bool:
        """Partitioned iteration (``iterations > 1``): each step is repeated until the interface
        displacement converges (module docstring)."""
        return self.iterations > 1

    @property
    def max_iterations(self) -> int:
        return self.iterations

    def __repr__(self) -> str:
        return (f"StructureCoupling(fluid={self.first!r}, structure={self.second!r}, walls={self.walls!r}, "
                f"wall_acceleration={self.wall_acceleration!r}, iterations={self.iterations!r}, "
                f"tolerance={self.tolerance!r}, relaxation={self.relaxation!r}, contact={self.contact!r})")

    # ------------------------------------------------------------------ validation
    def problems(self, scene: SceneView) -> list[str]:
        owner = f"StructureCoupling {self.name!r}"
        out = super().problems(scene)
        bodies = {b.name: b for b in scene.bodies}
        if self.first in bodies and not isinstance(bodies[self.first], FluidBody):
            out.append(f"{owner}: {self.first!r} must be a FluidBody (the slave side), got "
                       f"{type(bodies[self.first]).__name__}")
        if self.walls is not None and self.first in bodies:
            out += self.capability_problems(bodies[self.first], DrivesWalls, "drive wall particles riding on a "
                                            "structure", "with walls=")
        if self.iterates and self.second in bodies:
            out += self.capability_problems(bodies[self.second], CarriesStepEndLoad, "repeat a step with the load "
                                            "at the step's end", "with iterations > 1")
        if self.walls is not None:
            w = bodies.get(self.walls)
            if not isinstance(w, WallBody):
                out.append(f"{owner}: walls={self.walls!r} names no WallBody of the scene")
            elif w.follows != self.second:
                out.append(f"{owner}: the wall body {self.walls!r} must follow {self.second!r} (build it with "
                           f"WallBody.on_surface(..., follows={self.second!r})), it follows {w.follows!r}")
            elif (isinstance(w.footprints, SurfacePoints) and w.dim != 2) or (
                    isinstance(w.footprints, TrianglePoints) and w.dim != 3):
                out.append(f"{owner}: the wall body {self.walls!r} is {w.dim}D but its footprints are those of a "
                           f"{5 - w.dim}D surface; build it with WallBody.on_surface(...) on the structure's surface")
        out += [p.replace("PenaltyContact", owner + ": contact", 1) for p in self.contact.problems(scene)
                if "no body named" not in p]
        if not (isinstance(self.wall_acceleration, (int, float)) and 0.0 <= self.wall_acceleration <= 1.0):
            out.append(f"{owner}: wall_acceleration is the share of the structure's acceleration the wall pressure "
                       f"sees, in [0, 1]; got {self.wall_acceleration!r}")
        if not (isinstance(self.iterations, int) and self.iterations >= 1):
            out.append(f"{owner}: iterations must be a positive integer (1: explicit coupling), got {self.iterations!r}")
        if not (isinstance(self.tolerance, (int, float)) and self.tolerance > 0):
            out.append(f"{owner}: tolerance must be positive (m, the CRMS of the interface residual), got "
                       f"{self.tolerance!r}")
        if not (isinstance(self.relaxation, (int, float)) and 0.0 < self.relaxation <= 1.0):
            out.append(f"{owner}: relaxation must be in (0, 1], got {self.relaxation!r}")
        if self.iterates and self.walls is None:
            out.append(f"{owner}: the partitioned iteration relaxes the wall particles riding on the structure; "
                       "give walls=")
        return out

    def setup(self, scene: SceneView) -> None:
        """The riding wall particles' anchors and footprints (from the wall body), and the
        reaction records in the scene's dimension."""
        if scene.dim in (2, 3) and self.reaction.shape != (scene.dim,) and not np.any(self.reaction):
            self.reaction, self.contact_force = np.zeros(scene.dim), np.zeros(scene.dim)
        if self.walls is not None:
            w = next(b for b in scene.bodies if b.name == self.walls)
            self._anchors = np.asarray(w.anchors, dtype=float)
            self._footprints = w.footprints
        self.contact.setup(scene)

    # ------------------------------------------------------------------ per step
    def exchange(self, t: float, first: Solver, second: Solver) -> None:
        """Wall particles to the structure's surface at ``t``; penalty contact both ways."""
        t0 = time.perf_counter()
        if self.walls is not None:
            surf = second.surface(self.second)
            fp = self._footprints
            if fp is None or fp.average.shape[1] != surf.positions.shape[0]:
                raise ValueError(f"StructureCoupling {self.name!r}: the wall particles of {self.walls!r} were built on "
                                 f"a surface of {None if fp is None else fp.average.shape[1]} nodes, but "
                                 f"{self.second!r} has {surf.positions.shape[0]}; build them from that body's surface")
            x, v, a, n = riding_kinematics(surf, fp, self._anchors)
            if self.iterates:
                x, v, a = self._relaxed(x, v, a)
            if self._previous is not None and t > self._previous[0]:
                # what the fluid's step sees: the structure's motion over the step, not the
                # instantaneous state of its sub-steps (whose stiff modes ring)
                t_old, x_old, v_old, dt_old = self._previous
                dt = t - t_old
                v = (x - x_old) / dt
                a = (v - v_old) / (0.5 * (dt + dt_old)) if dt_old > 0 else a
                self._pending = (t, x, v, dt)
            else:
                self._pending = (t, x, v, 0.0)
            if not self.iterates:
                self._previous = self._pending
            a = float(self.wall_acceleration) * a
            first.drive_walls(self.walls, t, x, v, a, n)
        t1 = time.perf_counter()
        self.contact.exchange(t, first, second)
        self.seconds["walls"] += t1 - t0
        self.seconds["contact"] += time.perf_counter() - t1

    def after_step(self, t: float, first: Solver, second: Solver) -> None:
        """The fluid's reaction on the wall particles to the structure's surface nodes."""
        if self.walls is None:
            self._record(t)
            return
        t0 = time.perf_counter()
        f_w = first.wall_reactions(self.walls)
        # the transpose of the map that placed them: each particle's force spread over the
        # surface nodes of its footprint (virtual work; the total is kept exactly)
        point = self._anchors[:, 3].astype(np.int64)
        per_point = np.zeros((self._footprints.average.shape[0], f_w.shape[1]))
        np.add.at(per_point, point, f_w)
        second.add_surface_forces(self.second, self._footprints.average.T @ per_point)
        self.reaction = f_w.sum(axis=0)
        self.seconds["reaction"] += time.perf_counter() - t0
        self._record(t)

    # ------------------------------------------------------------------ partitioned iteration
    def _relaxed(self, x: FloatArray, v: FloatArray, a: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The interface of this pass: the structure's answer ``x*`` on the first, then
        ``x̃ ← x̃ + ω r`` with the residual ``r = x* − x̃`` and Aitken's factor (module docstring)."""
        if self._guess is None:
            self._residual = None
            self._guess = (x, v, a)
            return x, v, a
        gx, gv, ga = self._guess
        r = x - gx
        if self._residual is not None:
            dr = r - self._residual
            denom = float(np.sum(dr * dr))
            if denom > 0:
                self._omega = float(np.clip(-self._omega * float(np.sum(self._residual * dr)) / denom,
                                            AITKEN_RANGE[0], AITKEN_RANGE[1]))
        self._residual = r
        first = self._anchors[:, 2] <= self._anchors[:, 2].min() * (1 + 1e-9)   # the layer next to the surface
        self.crms = float(np.sqrt(np.mean(np.sum(r[first] ** 2, axis=1))))
        w = self._omega
        self._guess = (gx + w * r, gv + w * (v - gv), ga + w * (a - ga))
        return self._guess

    def begin_iteration(self, k: int, t: float, dt: float, first: Solver, second: Solver) -> None:
        """Pass ``k``: from the second on, the structure advances with the load the fluid gave in
        the pass before, at the step's end (an implicit structure, Newmark, solves with it)."""
        if k == 0:
            self._guess, self._residual, self.crms = None, None, float("nan")
            self._omega = float(np.clip(self._omega, AITKEN_RANGE[0], self.relaxation))
        elif self._load is not None:
            second.set_step_end_load(self.second, self._load)

    def end_iteration(self, k: int, t: float, first: Solver, second: Solver) -> bool:
        """Converged when the CRMS of the interface residual is below ``tolerance`` (from the second
        pass on), or at the last pass; the step is then accepted."""
        self._load = second.step_end_load(self.second)
        done = (k >= 1 and self.crms < self.tolerance) or k + 1 >= self.iterations
        if done:
            if not (k >= 1 and self.crms < self.tolerance):
                self.unconverged_steps += 1
            self.passes.append(k + 1)
            self._previous = self._pending
            self._load = None
        return done

    def _record(self, t: float) -> None:
        # on the structure
        contact = np.asarray(self.contact.last.get("force", np.zeros_like(self.reaction)), dtype=float)
        self.contact_force = contact
        load = float(np.linalg.norm(self.reaction + contact))
        if load > self.peak_load:
            self.peak_load, self.time_of_peak_load = load, float(t)

    def stable_time_step(self) -> float:
        return self.contact.stable_time_step()

    def observables(self) -> dict[str, float]:
        """The contact's: ``<name>_contact_energy`` (J, per unit depth in 2D)."""
        return self.contact.observables()

    # ------------------------------------------------------------------ restart and report
    def state_dict(self) -> dict[str, Any]:
        prev = None
        if self._previous is not None:
            t_p, x_p, v_p, dt_p = self._previous
            prev = [float(t_p), np.asarray(x_p).tolist(), np.asarray(v_p).tolist(), float(dt_p)]
        return {"contact": self.contact.state_dict(), "reaction": self.reaction.tolist(),
                "peak_load": self.peak_load, "time_of_peak_load": self.time_of_peak_load, "previous": prev,
                "omega": self._omega, "passes": list(self.passes), "unconverged_steps": self.unconverged_steps}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.contact.load_state_dict(d["contact"])
        self.reaction = np.asarray(d["reaction"], dtype=float)
        self.peak_load, self.time_of_peak_load = float(d["peak_load"]), d["time_of_peak_load"]
        prev = d.get("previous")
        self._previous = None if prev is None else (prev[0], np.asarray(prev[1], dtype=float),
                                                    np.asarray(prev[2], dtype=float), prev[3])
        self._omega = float(d.get("omega", self.relaxation))
        self.passes = list(d.get("passes", []))
        self.unconverged_steps = int(d.get("unconverged_steps", 0))

    def summary(self) -> dict[str, Any]:
        out = {"fluid": self.first, "structure": self.second, "walls": self.walls,
               "wall_acceleration": self.wall_acceleration,
               "last_wall_reaction_N": self.reaction.tolist(), "last_contact_force_N": self.contact_force.tolist(),
               "peak_load_N": self.peak_load, "time_of_peak_load_s": self.time_of_peak_load,
               "time_s": {k: round(v, 6) for k, v in self.seconds.items()},
               "contact": self.contact.summary()}
        if self.iterates:
            passes = np.asarray(self.passes) if self.passes else np.zeros(1)
            out["partitioned_iteration"] = {
                "tolerance_crms_m": self.tolerance, "max_passes": self.iterations, "initial_relaxation": self.relaxation,
                "passes_mean": float(passes.mean()), "passes_max": int(passes.max()),
                "steps_not_converged": self.unconverged_steps, "last_crms_m": self.crms,
                "last_relaxation": self._omega}
        return out
