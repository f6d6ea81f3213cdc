"""How each structure body advances over one outer step: one stepper per method.

=========================================================  ==========================================
module                                                     contents
=========================================================  ==========================================
:mod:`~mlsgalerkin.structure.steppers.base`                :class:`Stepper`: the body, the ramp of
                                                           the surface load over a step, counters
:mod:`~mlsgalerkin.structure.steppers.elastic_stepper`     :class:`ElasticStepper`: an elastic
                                                           body's ``u, v, a``, surface, energies
:mod:`~mlsgalerkin.structure.steppers.central_difference`  :class:`CentralDifference`: explicit,
                                                           sub-cycled, linear or total-Lagrangian
:mod:`~mlsgalerkin.structure.steppers.newmark`             :class:`Newmark`: implicit average
                                                           acceleration (linear)
:mod:`~mlsgalerkin.structure.steppers.rigid_motion`        :class:`RigidStepper` (what rigid bodies
                                                           share), :class:`RigidMotion`: about one
                                                           axis (hinge, vertical, fixed, 2D free)
:mod:`~mlsgalerkin.structure.steppers.free_rigid_motion`   :class:`FreeRigidMotion`: the free 3D
                                                           body (kick–rotate–kick)
:mod:`~mlsgalerkin.structure.steppers.rotation`            quaternions, the free rotation's splitting
=========================================================  ==========================================

:func:`stepper_for` picks the stepper of a body: an :class:`~mlsgalerkin.structure.ElasticBody`'s
``integrator`` (``"explicit"`` or ``"newmark"``) names its method; a
:class:`~mlsgalerkin.structure.RigidBody` free in 3D moves with :class:`FreeRigidMotion`, any other
with :class:`RigidMotion`.
"""

from __future__ import annotations

from mlsgalerkin.dynamics import Body
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.rigid import RigidBody
from mlsgalerkin.structure.steppers.base import Stepper
from mlsgalerkin.structure.steppers.central_difference import CentralDifference
from mlsgalerkin.structure.steppers.elastic_stepper import ElasticStepper
from mlsgalerkin.structure.steppers.free_rigid_motion import FreeRigidMotion
from mlsgalerkin.structure.steppers.newmark import Newmark
from mlsgalerkin.structure.steppers.rigid_motion import RigidMotion, RigidStepper

__all__ = ["STEPPERS", "CentralDifference", "ElasticStepper", "FreeRigidMotion", "Newmark", "RigidMotion",
           "RigidStepper", "Stepper", "stepper_for"]

#: The stepper class of each elastic body's ``integrator``.
STEPPERS: dict[str, type[ElasticStepper]] = {"explicit": CentralDifference, "newmark": Newmark}


def stepper_for(body: Body) -> Stepper:
    """A new stepper of ``body`` at rest (its state at the start of a run)."""
    if isinstance(body, ElasticBody):
        return STEPPERS[body.integrator](body)
    if isinstance(body, RigidBody):
        return FreeRigidMotion(body) if body.free_rotation else RigidMotion(body)
    raise TypeError(f"body {body.name!r}: the structure steppers advance ElasticBody and RigidBody, not "
                    f"{type(body).__name__}")
