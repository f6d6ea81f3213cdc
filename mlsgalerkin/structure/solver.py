r""":class:`StructureSolver`: advances the elastic and rigid bodies of a scene in the run loop.

Per outer step (:mod:`mlsgalerkin.dynamics`):

- ``begin_step(t, Δt)``: every body advances to ``t + Δt`` with the surface forces of the last
  exchange held (:mod:`mlsgalerkin.structure.integrators`: sub-cycled central differences,
  Newmark, or rigid-body Verlet, with the splitting of Dullweber, Leimkuhler & McLachlan 1997
  for the rotation of a free 3D body);
- the interactions read each body's :class:`~mlsgalerkin.dynamics.Surface` at ``t + Δt``
  (positions, velocities, accelerations, segments, nodal masses) and add forces to its surface
  nodes (cleared first, then accumulated over the exchange and the after-step exchange);
- ``end_step``: nothing more to do; those forces drive the next step.

The solver takes any outer step (``stable_time_step()`` is ``scene.dt_max``, or ``inf``; a scene of
structures alone must give ``dt_max``): an explicit elastic body sub-cycles at its own limit,
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
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Body, Solver, Surface
from mlsgalerkin.structure.checks import (
    LargeRotationWarning,
    rotation_operator,
    rotation_warning,
    structure_scene_problems,
)
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.integrators import ElasticMotion, RigidMotion
from mlsgalerkin.structure.rigid import RigidBody

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.scene import Scene

__all__ = ["StructureSolver", "StructureState"]

Motion = ElasticMotion | RigidMotion


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
        """The state and integrator of body ``name``."""
        return self.motions[name]

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

    def health(self, limits: Any) -> dict | None:
        for name, m in self.motions.items():
            if not m.finite():
                return {"quantity": "structure displacement or velocity", "body": name,
                        "hint": "the structure's state is not finite: lower the time step or the contact stiffness"}
        return None


class StructureSolver(Solver):
    """Advances the :class:`ElasticBody` and :class:`RigidBody` bodies of a scene (module docstring)."""

    key = "structure"

    @classmethod
    def problems(cls, bodies: list[Body], scene: Scene) -> list[str]:
        out = []
        if scene.dt_max is None and all(isinstance(b, (ElasticBody, RigidBody)) for b in scene.bodies):
            out.append("a scene of structures alone needs an outer time step: set dt_max= (s); the structure "
                       "solver sub-cycles inside whatever step it is given")
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

    def __init__(self, bodies: list[Body], scene: Scene) -> None:
        self.scene = scene
        self._state = StructureState({b.name: (ElasticMotion(b) if isinstance(b, ElasticBody) else RigidMotion(b))
                                      for b in bodies})
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
        """``scene.dt_max`` if given, else ``inf``: a structure takes whatever outer step the other
        solvers and the interactions allow (it sub-cycles; Newmark and rigid bodies need none)."""
        return math.inf if self.scene.dt_max is None else float(self.scene.dt_max)

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
