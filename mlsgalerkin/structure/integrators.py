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

import importlib
import warnings
from typing import Any

__all__: list[str] = []

#: Old name → (module under mlsgalerkin.structure.steppers, new name).
_MOVED = {
    "ElasticMotion": ("", "stepper_for"),
    "RigidMotion": ("", "stepper_for"),
    "SUBSTEP_SAFETY": ("central_difference", "SUBSTEP_SAFETY"),
    "NONLINEAR_ORDER": ("central_difference", "NONLINEAR_ORDER"),
    "NEWMARK_REUSE": ("newmark", "NEWMARK_REUSE"),
    "NEWMARK_MARGIN": ("newmark", "NEWMARK_MARGIN"),
    "RIGID_PHASE_PER_SUBSTEP": ("rigid_motion", "RIGID_PHASE_PER_SUBSTEP"),
    "FREE_ROTATION_SPLITTING": ("rotation", "FREE_ROTATION_SPLITTING"),
    "free_rotation": ("rotation", "free_rotation"),
    "quaternion_matrix": ("rotation", "quaternion_matrix"),
}


def __getattr__(name: str) -> Any:
    if name not in _MOVED:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, new = _MOVED[name]
    where = "mlsgalerkin.structure.steppers" + (f".{module}" if module else "")
    warnings.warn(f"mlsgalerkin.structure.integrators.{name} is deprecated; use {where}.{new}",
                  DeprecationWarning, stacklevel=2)
    return getattr(importlib.import_module(where), new)
