"""Deprecated: the structure steppers live in :mod:`mlsgalerkin.structure.steppers`, one module
per method. Every old name still imports from here for one release, with a
``DeprecationWarning`` naming its new home:

==========================  =====================================================================
old name                    new name
==========================  =====================================================================
``ElasticMotion(body)``     ``steppers.stepper_for(body)`` (a ``CentralDifference`` or ``Newmark``)
``RigidMotion(body)``       ``steppers.stepper_for(body)`` (a ``RigidMotion`` or ``FreeRigidMotion``)
``SUBSTEP_SAFETY``          ``steppers.central_difference.SUBSTEP_SAFETY``
``NONLINEAR_ORDER``         ``steppers.central_difference.NONLINEAR_ORDER``
``NEWMARK_REUSE``           ``steppers.newmark.NEWMARK_REUSE``
``NEWMARK_MARGIN``          ``steppers.newmark.NEWMARK_MARGIN``
``RIGID_PHASE_PER_SUBSTEP`` ``steppers.rigid_motion.RIGID_PHASE_PER_SUBSTEP``
``FREE_ROTATION_SPLITTING`` ``steppers.rotation.FREE_ROTATION_SPLITTING``
``free_rotation``           ``steppers.rotation.free_rotation``
``quaternion_matrix``       ``steppers.rotation.quaternion_matrix``
==========================  =====================================================================
"""

from __future__ import annotations

from mlsgalerkin.deprecation import moved_names

__all__: list[str] = []

_STEPPERS = "mlsgalerkin.structure.steppers"
__getattr__ = moved_names(__name__, {
    "ElasticMotion": f"{_STEPPERS}:stepper_for",
    "RigidMotion": f"{_STEPPERS}:stepper_for",
    "SUBSTEP_SAFETY": f"{_STEPPERS}.central_difference",
    "NONLINEAR_ORDER": f"{_STEPPERS}.central_difference",
    "NEWMARK_REUSE": f"{_STEPPERS}.newmark",
    "NEWMARK_MARGIN": f"{_STEPPERS}.newmark",
    "RIGID_PHASE_PER_SUBSTEP": f"{_STEPPERS}.rigid_motion",
    "FREE_ROTATION_SPLITTING": f"{_STEPPERS}.rotation",
    "free_rotation": f"{_STEPPERS}.rotation",
    "quaternion_matrix": f"{_STEPPERS}.rotation",
})
