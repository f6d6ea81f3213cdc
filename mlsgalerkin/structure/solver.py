r""":class:`StructureSolver`: advances the elastic and rigid bodies of a scene in the run loop.

Per outer step (:mod:`mlsgalerkin.dynamics`):

- ``begin_step(t, Δt)``: every body's stepper advances it to ``t + Δt`` with the surface forces
  of the last exchange ramped over the step (:mod:`mlsgalerkin.structure.steppers`: sub-cycled
  central differences, Newmark, or rigid-body Verlet, with the splitting of Dullweber,
  Leimkuhler & McLachlan 1997 for the rotation of a free 3D body);
- the interactions read each body's :class:`~mlsgalerkin.dynamics.Surface` at ``t + Δt``
  (positions, velocities, accelerations, segments, nodal masses) and add forces to its surface
  nodes (cleared first, then accumulated over the exchange and the after-step exchange);
- ``end_step``: nothing more to do; those forces drive the next step.

The solver takes any outer step (``stable_time_step()`` is its scheme's ``dt_max``, or ``inf``; a
scene of structures alone must give ``StructureScheme(dt_max=...)``): an explicit elastic body sub-cycles at its own limit,
Newmark and rigid bodies need none. The coupling is explicit and
staggered; its time-step limit comes from the interactions (penalty contact) and the fluid.

Time-series columns per body ``<name>``: ``<name>_kinetic_energy``, ``<name>_strain_energy``
(elastic) or ``<name>_spring_energy`` (hinge), ``<name>_weight_potential``,
``<name>_surface_work`` (J per unit depth), the named points' ``<name>_<point>_ux|uy`` (m),
and for rigid bodies ``<name>_x|y|z`` (displacement of the centre of mass, m), ``_angle`` (rad),
``_vx|vy|vz`` (m/s), ``_omega`` (rad/s), ``_force_x|y|z`` (N) and ``_moment`` (N m) of the surface
forces; a free 3D body has the world vectors ``_omega_x|y|z`` (rad/s), ``_moment_x|y|z`` (N m)
and ``_angular_momentum_x|y|z`` (kg m²/s) instead of ``_omega`` and ``_moment``, and ``_angle``
is the angle of its rotation from rest. Frames: ``structure.pvd``, the mesh nodes (elastic) and
surface nodes (rigid) with displacement, velocity and the body index.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Body, Diagnosis, SceneView, Solver, Surface
from mlsgalerkin.structure.checks import (
    LargeRotationWarning,
    rotation_operator,
    rotation_warning,
    structure_scene_problems,
)
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.rigid import RigidBody
from mlsgalerkin.structure.scheme import StructureScheme
from mlsgalerkin.structure.steppers import Stepper, stepper_for

__all__ = ["StructureSolver", "StructureState"]

#: The state of one body in a run: its stepper (:mod:`mlsgalerkin.structure.steppers`).
Motion = Stepper


@dataclass
class StructureState:
    """The structure bodies of a run, by name (what monitors and probes see as
    ``state.systems["structure"]``)."""

    motions: dict[str, Motion] = field(default_factory=dict)
    frame_name: ClassVar[str] = "structure"

    @property
    def n(self) -> int:
        return 0  # structure nodes are not counted as particles in the throughput

    def body(self, name: str) -> Motion:
        """The stepper of body ``name``: its live state (an elastic body's ``u``, ``v``, ``a``; a
        rigid body's ``c``, ``V``, ``theta``, ``F``, ...) and how it advances."""
        return self.motions[name]

    def body_names(self) -> list[str]:
        """The names of the bodies with a live state here, in scene order."""
        return list(self.motions)

    def observables(self) -> dict[str, float]:
        row: dict[str, float] = {}
        for name, m in self.motions.items():
            row.update({f"{name}_{k}": v for k, v in m.observables().items()})
        return row

    def frame(self) -> tuple[NDArray[np.float64], dict[str, NDArray]]:
        parts = [(i, *m.frame()) for i, m in enumerate(self.motions.values())]
        points = np.concatenate([p for _, p, _ in parts])
        data = {k: np.concatenate([d[k] for _, _, d in parts]) for k in ("displacement", "velocity")}
        data["body"] = np.concatenate([np.full(p.shape[0], i, dtype=np.int32) for i, p, _ in parts])
        return points, data

    def frame_cells(self) -> list[tuple[str, np.ndarray]]:
        """The cells on :meth:`frame`'s points: each elastic body's mesh (``quad`` or ``triangle``
        on its vertices), each rigid body's surface segments (``line``)."""
        out, offset = [], 0
        for m in self.motions.values():
            kind, cells = m.frame_cells()
            out.append((kind, cells + offset))
            offset += m.n_frame_points
        return out

    def health(self, limits: Any) -> Diagnosis | None:
        """``None`` if every body is sound, else the :class:`~mlsgalerkin.dynamics.Diagnosis` of
        the first bad body: a frame node (mesh vertex, or rigid surface node) whose displacement
        or velocity is not finite, a state that is not finite elsewhere (the whole body), or —
        when ``limits.max_displacement`` (m) is set — the node displaced furthest beyond it.
        ``position`` is the node's rest position (``at_rest``)."""
        max_u = getattr(limits, "max_displacement", None)
        for name, m in self.motions.items():
            diag = _body_health(name, m, max_u)
            if diag is not None:
                return diag
        return None


#: What to try when a structure's state is unsound.
HINT = ("Try a smaller time step (dt_max), a smaller contact stiffness (alpha), or check the structure's "
        "material and supports.")


def _body_health(name: str, m: Motion, max_displacement: float | None) -> Diagnosis | None:
    """The diagnosis of one body (:meth:`StructureState.health`); reads only what the motion
    shows to monitors (``finite()``, ``frame()``)."""
    finite = m.finite()
    if finite and max_displacement is None:
        return None
    points, data = m.frame()
    u, v = np.asarray(data["displacement"]), np.asarray(data["velocity"])
    rest = _rest_positions(m, points, u)
    where = {"body": name, "system": "structure", "hint": HINT}
    for quantity, arr in (("displacement", u), ("velocity", v)):
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        if bad.size:
            k = int(bad[0])
            return Diagnosis(quantity=quantity, value=arr[k], problem="is not finite", point="node", index=k,
                             position=rest[k], at_rest=True, **where)
    if not finite:
        return Diagnosis(quantity="state", value=(), problem="is not finite (a degree of freedom off the frame "
                         "nodes, or the rigid motion)", **where)
    size = np.sqrt(np.einsum("ij,ij->i", u, u))
    k = int(np.argmax(size)) if size.size else 0
    if size.size and size[k] > max_displacement:
        return Diagnosis(quantity="displacement", value=u[k], limit=float(max_displacement), point="node", index=k,
                         problem=f"|u| = {size[k]:.4g} m exceeds {max_displacement:.4g} m", position=rest[k],
                         at_rest=True, **where)
    return None


def _rest_positions(m: Motion, points: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.float64]:
    """The frame nodes at rest (m): the mesh's vertices of an elastic body, the surface nodes of
    a rigid body; ``points − u`` for any other motion."""
    body = m.body
    if isinstance(body, ElasticBody):
        return np.asarray(body.mesh.p, dtype=float).T
    if isinstance(body, RigidBody):
        return np.asarray(body.surface.nodes, dtype=float)
    return points - u


class StructureSolver(Solver):
    """Advances the :class:`ElasticBody` and :class:`RigidBody` bodies of a scene (module docstring)."""

    key = "structure"
    scheme_class = StructureScheme

    @classmethod
    def problems(cls, bodies: list[Body], scheme: StructureScheme, scene: SceneView) -> list[str]:
        out = []
        if scheme.dt_max is None and all(isinstance(b, (ElasticBody, RigidBody)) for b in scene.bodies):
            out.append("a scene of structures alone needs an outer time step: list StructureScheme(dt_max=...) (s) "
                       "in the scene's schemes; the structure solver sub-cycles inside whatever step it is given")
        for b in bodies:
            if not isinstance(b, (ElasticBody, RigidBody)):
                out.append(f"body {b.name!r}: the structure solver advances ElasticBody and RigidBody, not "
                           f"{type(b).__name__}")
            if isinstance(b, ElasticBody) and b.clamped_dofs.size == 0 and b.integrator == "newmark":
                out.append(f"ElasticBody {b.name!r}: Newmark needs a clamped boundary (the free body's stiffness is "
                           "singular); give clamped= or use the explicit integrator")
        out += structure_scene_problems([b for b in bodies if isinstance(b, (ElasticBody, RigidBody))],
                                        [b for b in scene.bodies if all(b is not s for s in bodies)], t_end=scene.t_end)
        return out

    def __init__(self, bodies: list[Body], scheme: StructureScheme, scene: SceneView) -> None:
        self.scheme = scheme
        self._state = StructureState({b.name: stepper_for(b) for b in bodies})
        # linear bodies watched for rotations beyond small-strain theory (a warning, once per body)
        self._rotation = {b.name: rotation_operator(b.basis) for b in bodies
                          if isinstance(b, ElasticBody) and b.model == "linear"}

    @property
    def state(self) -> StructureState:
        return self._state

    def start(self) -> None:
        for m in self._state.motions.values():
            m.start()

    def stable_time_step(self) -> float:
        """The scheme's ``dt_max`` if given, else ``inf``: a structure takes whatever outer step the
        other solvers and the interactions allow (it sub-cycles; Newmark and rigid bodies need none)."""
        return math.inf if self.scheme.dt_max is None else float(self.scheme.dt_max)

    def begin_step(self, t: float, dt: float) -> None:
        for m in self._state.motions.values():
            m.advance(dt)

    def end_step(self, t: float, dt: float) -> None:
        """Nothing to advance: the forces of this step's exchanges drive the next step's
        ``begin_step``. Warns (:class:`~mlsgalerkin.structure.checks.LargeRotationWarning`, once
        per body) when a linear body's largest element rotation exceeds
        :data:`~mlsgalerkin.structure.checks.LINEAR_ROTATION_LIMIT`."""
        for name, R in list(self._rotation.items()):
            m = self._state.motions[name]
            message = rotation_warning(f"ElasticBody {name!r}", R, m.u, m.body.dim, t + dt)
            if message:
                warnings.warn(message, LargeRotationWarning, stacklevel=2)
                del self._rotation[name]

    def surface(self, body: str) -> Surface:
        return self._state.motions[body].surface()

    def add_surface_forces(self, body: str, forces: np.ndarray) -> None:
        m = self._state.motions[body]
        f = np.asarray(forces, dtype=float)
        expected = (m.n_surface, m.body.dim)
        if f.shape != expected:
            raise ValueError(f"structure body {body!r}: surface forces must have shape {expected}, got {f.shape}")
        m.add_forces(f)

    def step_end_load(self, body: str):
        """The surface load ``body`` received since the last clear (for a partitioned iteration)."""
        return self._state.motions[body].step_end_load()

    def set_step_end_load(self, body: str, load) -> None:
        """Advance ``body`` in the next step with ``load`` (from :meth:`step_end_load`) at the step's
        end: the structure's half of an implicit, partitioned coupling."""
        self._state.motions[body].set_step_end_load(load)

    def clear_surface_forces(self) -> None:
        for m in self._state.motions.values():
            m.clear_forces()

    def checkpoint(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {f"{name}__{k}": v for name, m in self._state.motions.items() for k, v in m.checkpoint().items()}
        return arrays, {"bodies": list(self._state.motions)}

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        if meta.get("bodies") != list(self._state.motions):
            raise ValueError(f"checkpoint holds the structure bodies {meta.get('bodies')} but the scene has "
                             f"{list(self._state.motions)}; restart with the scene that wrote it")
        for name, m in self._state.motions.items():
            prefix = f"{name}__"
            m.restore({k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)})

    def summary(self) -> dict[str, Any]:
        bodies = {name: m.summary() for name, m in self._state.motions.items()}
        return {"bodies": bodies, "time_s": sum(b["time_s"] for b in bodies.values())}
